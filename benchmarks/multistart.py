"""The main job from eight starts: are there better optima in the box?

``design solve problems/hold_time_multistart.yaml`` through the public API
on 2 worker processes: the main job's pattern search from the thesis's
design and from seven scrambled Sobol points of the variables' box. The
baseline a user would otherwise have is the single start from the thesis's
design (start 0, the main job's own path), measured in the same run: every
start's verified hold is given as a ratio to it and to the baseline
design's hold, with its peak force against the cap, its status and its
design, and the distinct optima the starts reached.

Prints a table and writes benchmarks/results/multistart.json.

    python -m benchmarks.multistart
"""

from __future__ import annotations

import os
import tempfile
import time
from pathlib import Path

import design  # noqa: F401  first: it sets one BLAS thread before numpy loads (design/__init__.py)

from benchmarks.results_file import machine, write_results
from design.api import solve

ROOT = Path(__file__).resolve().parents[1]
RESULTS = Path(__file__).parent / "results" / "multistart.json"
PROBLEM = ROOT / "problems" / "hold_time_multistart.yaml"
WORKERS = 2


def main() -> None:
    load = os.getloadavg()
    t0 = time.perf_counter()
    with tempfile.TemporaryDirectory() as out:
        result = solve(PROBLEM, out=out, workers=WORKERS,
                       progress=lambda message: print(f"  {message}", flush=True)).to_dict()
    wall = time.perf_counter() - t0
    ms = result["multistart"]
    baseline = result["baseline"]["hold_time_s"]
    single = next(r for r in ms["starts"] if r["start"] == 0)["verified_hold_time_s"]
    print(f"\n{'start':>5s} {'status':24s} {'verified hold':>13s} {'/ start 0':>9s} "
          f"{'/ baseline':>10s} {'peak (N)':>8s}")
    for r in ms["starts"]:
        hold = r["verified_hold_time_s"]
        print(f"{r['start']:5d} {r['status']:24s} {hold:11.4f} s {hold / single:9.3f} "
              f"{hold / baseline:10.3f} {r['verified_max_finger_force_N']:8.2f}")
    best = result["verification"]["hold_time_s"]
    print(f"\n{result['status']}: best verified hold {best:.4f} s = {best / single:.3f} x the "
          f"single start's {single:.4f} s, {best / baseline:.3f} x the baseline's "
          f"{baseline:.4f} s; {len(ms['optima'])} distinct optima; {wall:.1f} s on {WORKERS} "
          f"workers")
    write_results(RESULTS, {
        "machine": machine(load, at_end=True),
        "command": f"design solve {PROBLEM.relative_to(ROOT)} --workers {WORKERS} "
                   "(design.api.solve)",
        "workers": WORKERS, "wall_time_s": wall, "status": result["status"],
        "cap_N": result["verification"].get("cap_N"), "baseline_hold_time_s": baseline,
        "single_start_hold_time_s": single, "best_verified_hold_time_s": best,
        "best_over_single_start": best / single, "best_over_baseline": best / baseline,
        "starts": ms["starts"], "optima": ms["optima"], "same_optimum": ms["same_optimum"],
        "unverified_starts": ms["unverified_starts"], "seed": ms["seed"]})


if __name__ == "__main__":
    main()
