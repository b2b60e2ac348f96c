"""How the chapter V comparisons that fail depend on the finger friction µ_f:
run from the repository root,
``.venv/bin/python examples/validation/friction_sensitivity.py [--out DIR]``.

Each row is one of ``design reproduce``'s setups (spatial finger model,
designed phase) with only the finger/bird friction changed; the belt keeps
its own (0.4 for the birds, 1.16 for the football). Printed as a table and
written to ``DIR/friction_sensitivity.json`` (default
reports/validation_friction/). About 25 s on one core.

What it shows: at the thesis's µ_f the drums sweep the fingers across the
bird at 0.1-0.4 m/s, so every touching finger carries a sliding friction of
µ_f times its normal force, much of it along the finger's stiff axis; the
peak forces fall with µ_f, and the finger that carries the peak changes.
"""

from __future__ import annotations

import sys
import time
from dataclasses import replace

from design.reproduce.grasp import (FOOTBALL_START, football_setup, mean_bird_setup,
                                    simulate_all)
from design.reproduce.grasp_rows import DENSE, family_peaks, impulse_share, passes, touching
from study_output import parser as study_parser, write_rows

#: (case, setup builder of µ_f, the µ_f values run; the thesis's value first)
CASES = tuple(
    (f"mean bird, {label}",
     lambda mu, lower=lower: replace(mean_bird_setup(lower), finger_friction=mu), (0.4, 0.2, 0.0))
    for lower, label in (("soft", "soft lower fingers"), ("hard", "hard lower fingers"),
                         ("constant", "constant EI"))
) + ((f"football, X0 = {FOOTBALL_START} m", lambda mu: football_setup(FOOTBALL_START, mu),
      (1.16, 0.4, 0.0)),)


def row(case: str, mu: float, run) -> dict:
    s = run.summary
    peaks = family_peaks(run)
    return {"case": case, "finger_friction": mu, "fingers_touching": touching(run),
            "peak_finger": max(peaks, key=peaks.get), "peak_force_N": max(peaks.values()),
            "finger_peaks_N": peaks,
            "share_within_1_5_in": impulse_share(run, lambda r: abs(r.y[0]) <= DENSE),
            "centre_rise_m": s["centre_rise_m"], "hold_time_s": s["hold_time_s"],
            "passes": passes(run)}


def main(argv: list[str] | None = None) -> int:
    parser = study_parser(__doc__, "validation_friction")
    args = parser.parse_args(argv)
    rows, start = [], time.perf_counter()
    for case, build, values in CASES:
        for mu in values:
            run = simulate_all({case: build(mu)})[case]
            rows.append(row(case, mu, run))
            r = rows[-1]
            print(f"{case:32s} µ_f {mu:4.2f}  fingers {r['fingers_touching']:10s} peak "
                  f"{r['peak_finger']} {r['peak_force_N']:5.1f} N  "
                  f"4: {r['finger_peaks_N'].get('4', 0.0):5.1f} N  5: "
                  f"{r['finger_peaks_N'].get('5', 0.0):5.1f} N  within ±1.5 in "
                  f"{r['share_within_1_5_in']:.2f}  rise {1e3 * r['centre_rise_m']:5.1f} mm  "
                  f"{'passes' if r['passes'] else 'does not pass'}", flush=True)
    write_rows(args.out / "friction_sensitivity.json", rows, time.perf_counter() - start)
    return 0


if __name__ == "__main__":
    sys.exit(main())
