"""Whether the football statements that fail depend on the drum
phase, which the thesis does not print: run from the repository root,
``.venv/bin/python examples/validation/football_phase.py [--out DIR] [--workers N]``.

The football scenes of ``design reproduce`` (designed phase, fingers 1 and 2
tilted to the ball) are rerun with the drums turned on by 0°, 10° … 110° (a
full set period: Table 5-1's three sets repeat every 120°), each with the
spatial finger model and with the thesis's own (``planar-thesis``). At every
phase each §5.3 statement is judged by the reproduction's criteria
(design/reproduce/grasp_rows.py). Figure 5-17's µ is run both ways: fingers
only (the belt keeps 1.16, as the reproduction does) and, as eq. 4.40's one
symbol reads, fingers and belt together. Printed as tables and written to
``DIR/football_phase.json`` (default reports/validation_phase/). About 4
minutes with two workers.
"""

from __future__ import annotations

import sys
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import replace

import numpy as np

from design.reproduce.grasp import (FOOTBALL_START, OMEGA, SIZES_START, advanced,
                                    football_setup, simulate_all)
from design.reproduce.grasp_rows import (PEAK_FOOTBALL, RISE_FOOTBALL, back_off, family_peaks,
                                         near_reading, passes, x_end)
from study_output import parser as study_parser, write_rows

MODELS = ("spatial", "planar-thesis")
PHASES = tuple(range(0, 120, 10))
#: case: (start X0 m, finger µ, belt µ, finger 3's φx deg)
CASES = {"experiment": (FOOTBALL_START, 1.16, 1.16, 60.0),
         "X0 -0.381": (SIZES_START, 1.16, 1.16, 60.0),
         "finger µ 0.4": (SIZES_START, 0.4, 1.16, 60.0),
         "finger µ 0": (SIZES_START, 0.0, 1.16, 60.0),
         "µ 0.4 belt too": (SIZES_START, 0.4, 0.4, 60.0),
         "µ 0 belt too": (SIZES_START, 0.0, 0.0, 60.0),
         "φx 45": (SIZES_START, 1.16, 1.16, 45.0),
         "φx 70": (SIZES_START, 1.16, 1.16, 70.0)}


def run_phase(model: str, phase: float) -> list[dict]:
    """Every case with the drums turned on by ``phase`` degrees."""
    rows = []
    for case, (x0, mu, belt, phi_x) in CASES.items():
        s = football_setup(x0, mu, phi_x, model)
        s = replace(s, conveyor_friction=belt,
                    grasper=advanced(s.grasper, np.radians(phase) / OMEGA))
        run = simulate_all({case: s})[case]
        peaks = family_peaks(run)
        rows.append({"model": model, "phase_deg": phase, "case": case,
                     "ok": bool(run.trajectory.ok), "centre_rise_m": run.summary["centre_rise_m"],
                     "max_pitch_deg": float(np.degrees(run.summary["max_pitch_rad"])),
                     "passes": passes(run), "back_off_m": back_off(run), "x_end_m": x_end(run),
                     "peak_finger": max(peaks, key=peaks.get) if peaks else None,
                     "peak_force_N": max(peaks.values(), default=0.0), "finger_peaks_N": peaks})
    return rows


def statements(rows: list[dict]) -> dict[str, bool]:
    """§5.3's statements at one phase, judged as the reproduction judges them."""
    r = {row["case"]: row for row in rows}
    exp = r["experiment"]
    return {
        "rise 18 mm ±30 %": near_reading(exp["centre_rise_m"], RISE_FOOTBALL),
        "passes, no turnover": exp["passes"] and exp["max_pitch_deg"] < 90.0,
        "peak finger 4, 8.5 N ±30 %": exp["peak_finger"] == "4"
        and near_reading(exp["peak_force_N"], PEAK_FOOTBALL),
        "Fig 5-16": exp["passes"] and r["X0 -0.381"]["passes"],
        "Fig 5-17 (fingers)": not r["finger µ 0"]["passes"] and r["finger µ 0.4"]["passes"]
        and r["X0 -0.381"]["passes"],
        "Fig 5-17 (belt too)": not r["µ 0 belt too"]["passes"] and r["µ 0.4 belt too"]["passes"]
        and r["X0 -0.381"]["passes"],
        "Fig 5-18": not r["φx 45"]["passes"] and r["X0 -0.381"]["passes"]
        and r["φx 70"]["passes"]}


def main(argv: list[str] | None = None) -> int:
    parser = study_parser(__doc__, "validation_phase")
    parser.add_argument("--workers", type=int, default=2)
    args = parser.parse_args(argv)
    start, rows = time.perf_counter(), []
    with ProcessPoolExecutor(args.workers) as pool:
        futures = [pool.submit(run_phase, m, p) for m in MODELS for p in PHASES]
        for k, future in enumerate(as_completed(futures), 1):
            rows += future.result()
            print(f"{k}/{len(futures)} phases done, {time.perf_counter() - start:.0f} s",
                  flush=True)
    rows.sort(key=lambda r: (MODELS.index(r["model"]), r["phase_deg"], list(CASES).index(r["case"])))
    verdicts = {}
    for model in MODELS:
        print(f"\n{model}: rise mm / peak finger, N / passes, per phase offset")
        for phase in PHASES:
            at = [r for r in rows if r["model"] == model and r["phase_deg"] == phase]
            verdicts[f"{model} {phase}"] = met = statements(at)
            exp = at[0]
            print(f"{phase:4d}° rise {1e3 * exp['centre_rise_m']:6.1f}  peak "
                  f"{exp['peak_finger']} {exp['peak_force_N']:5.1f}  passes "
                  + " ".join(f"{r['case']}:{'y' if r['passes'] else 'n'}" for r in at)
                  + f"  met: {', '.join(k for k, v in met.items() if v) or 'none'}")
        every = [p for p in PHASES if all(verdicts[f"{model} {p}"].values())]
        print(f"{model}: phases meeting every statement: {every or 'none'}")
    write_rows(args.out / "football_phase.json", rows, time.perf_counter() - start,
               statements=verdicts)
    return 0


if __name__ == "__main__":
    sys.exit(main())
