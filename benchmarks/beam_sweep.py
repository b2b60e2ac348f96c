"""A 1000-load beam sweep through the public API against scipy's solve_bvp.

The target: ``design.simulate`` on a beam scene whose ``F`` is a list
of 1000 loads, default solver (collocation, 16 intervals of degree 4), on the
thesis's non-uniform finger (models/fingers/thesis_nonuniform_soft.yaml), at
least 50x faster per solve than ``scipy.integrate.solve_bvp(tol=1e-8)`` on
the same loads (warm-started along the sweep: benchmarks/beam.py's
``bvp_sweep``), with every load point within 1e-8 m of a high-accuracy
reference. Two load cases: the README's sweep (Table 2-3: F = 0.1..30 N,
α = 90°, at 76.2 mm) and problems/beam_sweep.yaml's direction and position
(F = 0..30 N, α = 60°, at 5 in).

Warm against warm: the first ``simulate`` call (it builds the sweep's
compiled library, or loads it from the cache) is reported apart; then
``simulate`` and ``solve_bvp`` sweeps alternate, ``--repeat`` times each, so
that both see the same load on the machine. Each sweep's wall time and CPU
time (``time.process_time``: every thread of this process) are recorded per
solve, with the machine's core count and load average. Errors: the largest
load-point distance from the reference (collocation on 128 intervals,
itself compared with solve_bvp at tol 1e-10), and the cases whose error
exceeds their ``error_estimate``; convergence: ``simulate``'s ``converged``
per case, ``solve_bvp``'s status per solve.

Prints a table and writes benchmarks/results/beam_sweep.json.

    python -m benchmarks.beam_sweep               # 5 repeats: 3 minutes on the loaded 2 cores
    python -m benchmarks.beam_sweep --repeat 2
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

import casadi as ca
import numpy as np

import design
from benchmarks.beam import bvp_sweep
from benchmarks.results_file import machine, write_results
from design.io.fingers import read_finger
from design.physics.beam import PointLoad
from design.reproduce.grasp import load_model
from design.solvers import compiled
from design.solvers.beam import solve_beam
from design.tradeoff.beam import REFERENCE_INTERVALS, tips

RESULTS = Path(__file__).parent / "results" / "beam_sweep.json"
FINGER_FILE = Path(__file__).resolve().parents[1] / "models" / "fingers" / \
    "thesis_nonuniform_soft.yaml"
LOADS = 1000
#: (forces, N; direction, degrees; load point, m)
CASES = {
    "table_2_3": (np.linspace(0.1, 30.0, LOADS), 90.0, 0.0762),
    "beam_sweep": (np.linspace(0.0, 30.0, LOADS), 60.0, 0.127),
}
BVP_TOL, CHECK_TOL = 1e-8, 1e-10
TARGET_SPEEDUP, TARGET_ERROR_M = 50.0, 1e-8


def clocked(fn) -> tuple[object, float, float]:
    """fn's result, its wall time and its CPU time (s)."""
    wall, cpu = time.perf_counter(), time.process_time()
    out = fn()
    return out, time.perf_counter() - wall, time.process_time() - cpu


def per_solve(times: list[tuple[float, float]], n: int) -> dict:
    """Wall and CPU time per solve (s): min and median over the sweeps, and each sweep's."""
    wall, cpu = (np.array(t) / n for t in zip(*times))
    return {"wall_min_s": wall.min(), "wall_median_s": float(np.median(wall)),
            "cpu_min_s": cpu.min(), "cpu_median_s": float(np.median(cpu)),
            "wall_s": wall, "cpu_s": cpu}


def run_case(name: str, repeat: int) -> dict:
    forces, alpha_deg, at = CASES[name]
    finger = load_model(read_finger, "fingers", FINGER_FILE.name)
    loads = [PointLoad(float(f), np.radians(alpha_deg), at) for f in forces]
    scene = {"kind": "beam", "name": f"sweep_{name}", "finger": str(FINGER_FILE),
             "load": {"F": [float(f) for f in forces], "alpha": f"{alpha_deg} deg", "at": at}}
    reference = solve_beam(finger, loads, "collocation", nodes=REFERENCE_INTERVALS)
    ref = tips(reference)
    check, check_status = bvp_sweep(finger, loads, CHECK_TOL)

    libraries = len(compiled.status.libraries)
    _, first_wall, first_cpu = clocked(lambda: design.simulate(scene))
    first = {"wall_s": first_wall, "cpu_s": first_cpu,
             "compiled": compiled.status.summary(libraries)}
    api_times, bvp_times, solve_times = [], [], []
    for _ in range(repeat):
        result, wall, cpu = clocked(lambda: design.simulate(scene).to_dict())
        api_times.append((wall, cpu))
        solve_times.append(result["solve_time_s"])
        (points, status), wall, cpu = clocked(lambda: bvp_sweep(finger, loads, BVP_TOL))
        bvp_times.append((wall, cpu))
    cases = result["cases"]
    got = np.array([[c["tip"]["x"], c["tip"]["y"]] for c in cases])
    api_err = np.linalg.norm(got - ref, axis=1)
    estimates = np.array([c["error_estimate"] for c in cases])
    api = {"method": "design.simulate, default solver", "solver": result["solver"],
           "max_error_m": api_err.max(), "converged": sum(c["converged"] for c in cases),
           "error_above_estimate": int(np.sum(api_err > estimates)),
           "max_error_estimate_m": estimates.max(),
           "newton_steps": np.bincount([c["iterations"] for c in cases]),
           "first_call": first, **per_solve(api_times, len(loads)),
           "solve_time_median_s": float(np.median(solve_times)) / len(loads)}
    bvp = {"method": f"scipy solve_bvp tol={BVP_TOL:g}",
           "max_error_m": np.linalg.norm(points - ref, axis=1).max(),
           "converged": int(np.sum(status == 0)), **per_solve(bvp_times, len(loads))}
    speedup = {f"{k}_{s}": bvp[f"{k}_{s}_s"] / api[f"{k}_{s}_s"]
               for k in ("wall", "cpu") for s in ("min", "median")}
    accurate = (api["max_error_m"] <= TARGET_ERROR_M and api["converged"] == len(loads)
                and api["error_above_estimate"] == 0)
    met = {k: bool(accurate and v >= TARGET_SPEEDUP) for k, v in speedup.items()}
    return {"loads": len(loads), "F_N": [forces[0], forces[-1]], "alpha_deg": alpha_deg,
            "at_m": at, "reference": {
                "method": f"collocation, {REFERENCE_INTERVALS} intervals",
                "max_error_estimate_m": max(s.error_estimate for s in reference),
                "converged": sum(s.converged for s in reference),
                "max_distance_to_solve_bvp_tol_1e-10_m": np.linalg.norm(check - ref, axis=1).max(),
                "solve_bvp_tol_1e-10_converged": int(np.sum(check_status == 0))},
            "api": api, "solve_bvp": bvp, "speedup": speedup, "target_met": met}


def run(repeat: int) -> dict:
    start = os.getloadavg()
    cases = {name: run_case(name, repeat) for name in CASES}
    return {"machine": {**machine(start, at_end=True), "casadi": ca.__version__},
            "repeat": repeat,
            "timing": "warm against warm: simulate's first call (compiled library built or "
                      "loaded) apart; then simulate and solve_bvp sweeps alternate; per solve = "
                      "sweep time / loads; CPU = time.process_time (all threads)",
            "target": {"speedup": TARGET_SPEEDUP, "max_error_m": TARGET_ERROR_M},
            "cases": cases}


def print_table(result: dict) -> None:
    m = result["machine"]
    print(f"{m['cores']} cores, load average {m['load_average_at_start'][0]:.2f} at the start, "
          f"{m['load_average_at_end'][0]:.2f} at the end; {result['repeat']} sweeps each")
    print(f"{'case':11} {'method':34} {'max error':>10} {'converged':>10} "
          f"{'wall/solve min, median':>24} {'CPU/solve min, median':>24}")
    for name, case in result["cases"].items():
        n = case["loads"]
        for row in (case["api"], case["solve_bvp"]):
            print(f"{name:11} {row['method']:34} {row['max_error_m']:10.1e} "
                  f"{row['converged']:>5}/{n:<4} "
                  f"{row['wall_min_s'] * 1e6:10.1f} {row['wall_median_s'] * 1e6:8.1f} µs "
                  f"{row['cpu_min_s'] * 1e6:10.1f} {row['cpu_median_s'] * 1e6:8.1f} µs")
        s, api = case["speedup"], case["api"]
        print(f"{'':11} {'speed-up (solve_bvp / simulate)':34} {'':10} {'':10} "
              f"{s['wall_min']:12.1f}x {s['wall_median']:7.1f}x "
              f"{s['cpu_min']:12.1f}x {s['cpu_median']:7.1f}x")
        print(f"{'':11} simulate: solver {api['solve_time_median_s'] * 1e6:.1f} µs of each solve "
              f"(median); first call {api['first_call']['wall_s']:.2f} s, libraries built "
              f"{api['first_call']['compiled']['libraries_built']}; errors above their estimate "
              f"{api['error_above_estimate']}; reference (collocation {REFERENCE_INTERVALS}) to "
              f"solve_bvp 1e-10: {case['reference']['max_distance_to_solve_bvp_tol_1e-10_m']:.1e} m")
        print(f"{'':11} target (≤ {TARGET_ERROR_M:g} m, ≥ {TARGET_SPEEDUP:g}x) met by "
              f"{', '.join(k for k, v in case['target_met'].items() if v) or 'no measure'}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=5)
    args = parser.parse_args()
    result = run(args.repeat)
    print_table(result)
    write_results(RESULTS, result)


if __name__ == "__main__":
    main()
