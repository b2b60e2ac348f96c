"""Which band and which "determined" rule would the fit benches support?

Every bench of tests/fit_benches.py with each kind of reading is fitted
once by ``design fit``'s fit (its data file written and read back, the
uniform elastica fit, the path of weights); its band is then recomputed
under other rules, without fitting again:

* the Bayesian band at the chosen weight over ``f`` (1: Wahba's band at the
  chosen weight; 10: the shipped rule, design/calibration/refinement.py's
  BAND_UNDERSMOOTHING; where GCV is least at the path's first weight, widened
  as shipped to cover the alternative fit), optionally widened by an estimate of the smoothing's
  bias, |ln c at the chosen weight - ln c k path steps smaller| (k = 2: a
  decade);
* EI called determined where that band is within ±T.

For each rule: over the smooth benches and over the stepped ones, how many
fits claim something that does not hold (a judged knot more than 10 % off,
or the band holding the truth at fewer than 90 % of them), how many claim
nothing, and how many judge half the finger or more. The shipped rule is
f = 10, no bias term, T = 0.25. The benches have been seen: this measures
the rules, it does not hold one out.

Prints a table and writes benchmarks/results/fit_bands.json (about 4
minutes on 2 cores).

    python -m benchmarks.fit_bands
"""

from __future__ import annotations

import os
import tempfile
from multiprocessing import get_context
from pathlib import Path

import design  # noqa: F401  first: it sets one BLAS thread before numpy loads (design/__init__.py)
import numpy as np

from benchmarks.results_file import machine, write_results
from design.calibration.refinement import BAND_UNDERSMOOTHING
from design.io.scene import load_fit
from design.run.finger_fit import DETERMINED_BAND, fit_finger
from tests.fit_benches import FAMILY, READINGS, STEPPED, judged_span, write_problem

RESULTS = Path(__file__).parent / "results" / "fit_bands.json"
FACTORS = (1.0, 3.0, 10.0)
BIAS_STEPS = (0, 2)
THRESHOLDS = (0.10, 0.15, 0.20, 0.25)


def refined(job: tuple[str, str]) -> dict:
    """One bench's refinement: its knots, fit, the truth, and the pieces of
    every rule's band (standard deviations of ln c at each factor, the bias
    terms)."""
    name, which = job
    with tempfile.TemporaryDirectory() as folder:
        problem = load_fit(write_problem(Path(folder), name, which))
    fit, data = fit_finger(problem).fit, problem.data
    knots = fit.knots
    sweep = fit.selection.sweep
    chosen = next(i for i, w in enumerate(sweep) if w is fit.selection.chosen)
    out = {"bench": name, "readings": which, "knots": knots, "reach": data.reach,
           "ei": 1.0 / fit.c, "truth": FAMILY[name].stiffness.ei(knots)}
    for k in BIAS_STEPS:
        out[f"bias{k}"] = np.abs(sweep[chosen].z - sweep[min(chosen + k, len(sweep) - 1)].z)
    for f in FACTORS:
        fit.selection.band_undersmoothing = f
        out[f"sd{f:g}"] = fit.selection.z_sd()
    return out


def claims(r: dict, factor: float, bias: int, threshold: float) -> tuple[int, bool, float]:
    """Under one rule: the knots judged, whether what is claimed holds, and
    the judged span's share of the length."""
    half = 1.96 * r[f"sd{factor:g}"] + r[f"bias{bias}"]
    determined = (r["knots"] <= r["reach"] + 1e-12) & (np.expm1(half) <= threshold)
    mask = judged_span(r["bench"], r["knots"], determined)
    if not mask.any():
        return 0, True, 0.0
    err = np.abs(r["ei"][mask] / r["truth"][mask] - 1)
    inside = np.abs(np.log(r["truth"][mask] / r["ei"][mask])) <= half[mask]
    span = (r["knots"][mask][-1] - r["knots"][mask][0]) / r["knots"][-1]
    return int(mask.sum()), bool(err.max() <= 0.10 and inside.mean() >= 0.9), float(span)


def main() -> None:
    load = os.getloadavg()
    jobs = [(n, w) for n in FAMILY for w in READINGS]
    with get_context("fork").Pool(2) as pool:
        fits = pool.map(refined, jobs)
    rows = []
    print(f"{'factor':>6s} {'bias':>4s} {'±T':>5s} | {'smooth: wrong':>13s} {'nothing':>7s} "
          f"{'half+':>5s} | {'stepped: wrong':>14s} {'nothing':>7s} {'half+':>5s}")
    for f in FACTORS:
        for b in BIAS_STEPS:
            for t in THRESHOLDS:
                row = {"factor": f, "bias_steps": b, "threshold": t,
                       "shipped": f == BAND_UNDERSMOOTHING and b == 0 and t == DETERMINED_BAND}
                for label, subset in (("smooth", [r for r in fits if r["bench"] not in STEPPED]),
                                      ("stepped", [r for r in fits if r["bench"] in STEPPED])):
                    c = [claims(r, f, b, t) for r in subset]
                    row[label] = {"fits": len(c), "wrong": sum(not ok for _, ok, _ in c),
                                  "nothing": sum(j == 0 for j, _, _ in c),
                                  "half_or_more": sum(s >= 0.5 for _, _, s in c)}
                rows.append(row)
                s, p = row["smooth"], row["stepped"]
                print(f"{f:6g} {b:4d} {t:5.2f} | {s['wrong']:13d} {s['nothing']:7d} "
                      f"{s['half_or_more']:5d} | {p['wrong']:14d} {p['nothing']:7d} "
                      f"{p['half_or_more']:5d}{'  (shipped)' if row['shipped'] else ''}")
    write_results(RESULTS, {
        "machine": machine(load),
        "fits": len(fits), "rows": rows})


if __name__ == "__main__":
    main()
