"""Whether the football statements that fail depend on the drum
phase, which the thesis does not print: run from the repository root,
``.venv/bin/python examples/validation/football_phase.py [--out DIR] [--workers N]
[--models M ...] [--cases C ...]``.

The football scenes of ``design reproduce`` (Table 5-1's layout, the
football's one drum timing) are rerun with the drums turned on by 0°, 10° …
110° (a full set period: Table 5-1's three sets repeat every 120°), each with
the spatial finger model and with the thesis's own (``planar-thesis``), or
the ``--models`` and ``--cases`` named. At every phase each §5.3 statement
whose cases were run is judged by the reproduction's criteria
(design/reproduce/grasp_rows.py). Figure 5-17's µ is run both ways: fingers
only (the belt keeps 1.16, as the reproduction does) and, as eq. 4.40's one
symbol reads, fingers and belt together. Printed as tables and written to
``DIR/football_phase.json`` (default reports/validation_phase/).
"""

from __future__ import annotations

import sys
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import replace

import numpy as np

from design.reproduce.grasp import FOOTBALL_START, SIZES_START, football_setup, simulate_all
from design.reproduce.grasp_rows import (PEAK_FOOTBALL, RISE_FOOTBALL, RUN_BUDGET, back_off,
                                         family_peaks, near_reading, passes, x_end)
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


def run_phase(model: str, phase: float, cases: tuple[str, ...] = tuple(CASES),
              budget: float = RUN_BUDGET) -> list[dict]:
    """The ``cases`` with the drums turned on by ``phase`` degrees, each
    within ``budget`` s of wall time (one it stops is reported as such)."""
    rows = []
    for case in cases:
        x0, mu, belt, phi_x = CASES[case]
        s = replace(football_setup(x0, mu, phi_x, model, phase=phase), conveyor_friction=belt)
        run = simulate_all({case: s}, budget=budget)[case]
        peaks = family_peaks(run)
        rows.append({"model": model, "phase_deg": phase, "case": case,
                     "ok": bool(run.trajectory.ok),
                     "finished": not run.trajectory.out_of_time,
                     "centre_rise_m": run.summary["centre_rise_m"],
                     "max_pitch_deg": float(np.degrees(run.summary["max_pitch_rad"])),
                     "passes": passes(run), "back_off_m": back_off(run), "x_end_m": x_end(run),
                     "peak_finger": max(peaks, key=peaks.get) if peaks else None,
                     "peak_force_N": max(peaks.values(), default=0.0), "finger_peaks_N": peaks})
    return rows


#: §5.3's statements: (the cases each needs, whether they meet it)
STATEMENTS = {
    "rise 18 mm ±30 %": (("experiment",),
                         lambda r: near_reading(r["experiment"]["centre_rise_m"], RISE_FOOTBALL)),
    "passes, no turnover": (("experiment",), lambda r: r["experiment"]["passes"]
                            and r["experiment"]["max_pitch_deg"] < 90.0),
    "peak finger 4, 8.5 N ±30 %": (("experiment",), lambda r: r["experiment"]["peak_finger"] == "4"
                                   and near_reading(r["experiment"]["peak_force_N"],
                                                    PEAK_FOOTBALL)),
    "Fig 5-16": (("experiment", "X0 -0.381"), lambda r: all(v["passes"] for v in r.values())),
    "Fig 5-17 (fingers)": (("finger µ 0", "finger µ 0.4", "X0 -0.381"), lambda r: not r[
        "finger µ 0"]["passes"] and r["finger µ 0.4"]["passes"] and r["X0 -0.381"]["passes"]),
    "Fig 5-17 (belt too)": (("µ 0 belt too", "µ 0.4 belt too", "X0 -0.381"), lambda r: not r[
        "µ 0 belt too"]["passes"] and r["µ 0.4 belt too"]["passes"] and r["X0 -0.381"]["passes"]),
    "Fig 5-18": (("φx 45", "X0 -0.381", "φx 70"), lambda r: not r["φx 45"]["passes"]
                 and r["X0 -0.381"]["passes"] and r["φx 70"]["passes"])}


def statements(rows: list[dict]) -> dict[str, bool]:
    """§5.3's statements at one phase whose cases were all run, judged as the
    reproduction judges them."""
    r = {row["case"]: row for row in rows}
    return {name: met({c: r[c] for c in cases}) for name, (cases, met) in STATEMENTS.items()
            if all(c in r for c in cases)}


def main(argv: list[str] | None = None) -> int:
    parser = study_parser(__doc__, "validation_phase")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--models", nargs="+", choices=MODELS, default=list(MODELS))
    parser.add_argument("--cases", nargs="+", choices=list(CASES), default=list(CASES))
    parser.add_argument("--budget", type=float, default=RUN_BUDGET,
                        help="wall time allowed per run, s (default: the reproduction's)")
    args = parser.parse_args(argv)
    start, rows = time.perf_counter(), []
    cases = tuple(c for c in CASES if c in args.cases)
    with ProcessPoolExecutor(args.workers) as pool:
        futures = [pool.submit(run_phase, m, p, cases, args.budget) for m in args.models
                   for p in PHASES]
        for k, future in enumerate(as_completed(futures), 1):
            rows += future.result()
            print(f"{k}/{len(futures)} phases done, {time.perf_counter() - start:.0f} s",
                  flush=True)
    rows.sort(key=lambda r: (MODELS.index(r["model"]), r["phase_deg"],
                             list(CASES).index(r["case"])))
    verdicts = {}
    for model in args.models:
        print(f"\n{model}: rise mm / peak finger, N / passes, per phase offset")
        for phase in PHASES:
            at = [r for r in rows if r["model"] == model and r["phase_deg"] == phase]
            verdicts[f"{model} {phase}"] = met = statements(at)
            exp = at[0]
            print(f"{phase:4d}° {exp['case']}: rise {1e3 * exp['centre_rise_m']:6.1f}  peak "
                  f"{exp['peak_finger']} {exp['peak_force_N']:5.1f}  passes "
                  + " ".join(f"{r['case']}:{'y' if r['passes'] else 'n'}" for r in at)
                  + f"  met: {', '.join(k for k, v in met.items() if v) or 'none'}")
        every = [p for p in PHASES if verdicts[f"{model} {p}"]
                 and all(verdicts[f"{model} {p}"].values())]
        print(f"{model}: phases meeting every statement: {every or 'none'}")
    write_rows(args.out / "football_phase.json", rows, time.perf_counter() - start,
               statements=verdicts)
    return 0


if __name__ == "__main__":
    sys.exit(main())
