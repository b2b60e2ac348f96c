"""The whole flock: one design for Table 5-5's birds, and the line's rate.

``population``: ``design solve problems/hold_time_population.yaml`` through
the public API, each bird verified at 4x finer resolution; the baseline a
user would otherwise have is the thesis's design, and the mean bird's own
optimum (the same search on the design bird alone, in the same run) is
beside it: per bird, the hold, peak and jam of each.

``line``: ``design solve problems/line_speed.yaml``: per number of finger
sets the highest verified rate (birds/min) with every bird held the
problem's ``min_hold`` under the cap, against the thesis's 60 birds/min (the
baseline design, measured in the same run), and the Pareto front.

Each prints a table and writes its entry of benchmarks/results/flock.json
(the others are kept), with the wall time and the number of workers: on 2
workers the study's entry, on any other number its own
(``line_on_1_workers``), so that the page compares the wall times.

    python -m benchmarks.flock population [--workers 2] [--out DIR]
    python -m benchmarks.flock line [--workers 2] [--out DIR]
"""

from __future__ import annotations

import argparse
import json
from collections import Counter
import os
import tempfile
import time
from datetime import datetime, timezone
from pathlib import Path

import design  # noqa: F401  first: it sets one BLAS thread before numpy loads (design/__init__.py)

from benchmarks.results_file import machine, write_results
from design.api import solve
from design.solvers.optimize.feasibility import answered

ROOT = Path(__file__).resolve().parents[1]
RESULTS = Path(__file__).parent / "results" / "flock.json"
PROBLEMS = {"population": ROOT / "problems" / "hold_time_population.yaml",
            "line": ROOT / "problems" / "line_speed.yaml"}


def population_entry(result: dict) -> dict:
    p = result["population"]
    labels = ("baseline", "single_bird_optimum", "robust_optimum")
    print(f"\n{'bird':20s}" + "".join(f" {label + ' hold/peak/jam':>44s}" for label in labels))
    for b in p["birds"]:
        print(f"{b['bird']:20s}" + "".join(
            f" {b[f'{label}_hold_time_s']:8.4f} s {b[f'{label}_max_finger_force_N']:7.2f} N "
            f"{'jam' if b[f'{label}_jam'] != 'none' else 'no jam':>6s}" + " " * 15
            for label in labels))
    search = result["solver"]["search"]
    screen = search if answered(search) else None
    if screen:
        print(f"\nfeasibility screen on {screen['bird']}: start, simulations, within limits, "
              f"jammed, hold (s), peak (N)")
        for r in screen["starts"]:
            print(f"{r['start_index']:5d} {r['simulations']:5d} {str(r['within']):>6s} "
                  f"{r['jammed']:3d} {r['hold_time_s']:8.4f} {r['max_finger_force_N']:8.2f}")
    ruled = Counter(h.get("ruled_out_by") for h in result["solver"]["history"])
    ruled.pop(None, None)
    return {"cap_N": result["cap"]["N"], "birds": p["birds"],
            "hold_time_s": p["hold_time_s"], "limiting_bird": p["limiting_bird"],
            "single_bird_design": p["single_bird_design"], "robust_design": result["design"],
            "simulations": search["simulations"],
            "bird_simulations": search.get("bird_simulations"),
            "candidates_ruled_out_by": dict(ruled), "screen": screen,
            "profile": result["profile"]}


def line_entry(result: dict) -> dict:
    line = result["line"]
    print(f"\n{'sets':>4s} {'status':28s} {'rate (1/min)':>12s} {'rpm':>6s} {'belt (m/s)':>10s} "
          f"{'dx (m)':>7s} {'worst hold':>10s} {'peak (N)':>8s}")
    for r in line["cases"]:
        print(f"{r['finger_sets']:4d} {r['status']:28s} {r['line_rate_per_min']:12.1f} "
              f"{r['drum_speed_rpm']:6.1f} {r['belt_speed_m_s']:10.3f} {r['bird_spacing_m']:7.3f} "
              f"{r['worst_hold_time_s']:8.4f} s {r['max_finger_force_N']:8.2f}")
    base = line["baseline"]["line_rate_per_min"]
    return {"cap_N": result["cap"]["N"], "min_hold_s": result["objective"]["min_hold_s"],
            "baseline_rate_per_min": base, "answer_rate_per_min": result["line_rate_per_min"],
            "answer_over_baseline": result["line_rate_per_min"] / base,
            "cases": line["cases"], "limit": line["limit"], "baseline": line["baseline"],
            "optimum_birds": line["optimum_birds"], "design": result["design"],
            "pareto": result["pareto"]}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("study", choices=sorted(PROBLEMS))
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--out", type=Path, help="keep the run's files (result.json, report) "
                        "here; by default they go to a temporary folder")
    args = parser.parse_args()
    problem = PROBLEMS[args.study]
    load = os.getloadavg()
    t0 = time.perf_counter()
    with tempfile.TemporaryDirectory() as scratch:
        result = solve(problem, out=args.out or scratch, workers=args.workers,
                       progress=lambda message: print(f"  {message}", flush=True)).to_dict()
    wall = time.perf_counter() - t0
    entry = (population_entry if args.study == "population" else line_entry)(result)
    print(f"\n{result['status']}: {result['message']}\n{wall:.1f} s on {args.workers} workers")
    kept = json.loads(RESULTS.read_text()) if RESULTS.exists() else {}
    kept.pop("measured_at", None)
    key = args.study if args.workers == 2 else f"{args.study}_on_{args.workers}_workers"
    write_results(RESULTS, {**kept, key: {
        "measured_at": datetime.now(timezone.utc).date().isoformat(),
        "machine": machine(load, at_end=True),
        "command": f"design solve {problem.relative_to(ROOT)} --workers {args.workers} "
                   "(design.api.solve)",
        "workers": args.workers, "wall_time_s": wall, "status": result["status"],
        "message": result["message"], **entry}})


if __name__ == "__main__":
    main()
