"""The pattern search's lattice: what each finer step costs the main job and
what it gains.

``design solve problems/hold_time.yaml`` through the public API with the
search's lattice (``solver: {lattice: n}``, each variable's box in n units,
the finest step 1/n) at 16, 32 and 64, each in this process one after the
other, the problem otherwise as shipped. A coarser lattice takes the finer
one's steps and ends sooner, on a coarser point. The baseline a user would
otherwise have is the pattern search's default lattice (64), measured in the
same run: each row's wall time and verified hold are given as ratios to it.

Prints a table and writes benchmarks/results/lattice.json.

    python -m benchmarks.lattice
"""

from __future__ import annotations

import os
import tempfile
import time
from pathlib import Path

import design  # noqa: F401  first: it sets one BLAS thread before numpy loads (design/__init__.py)

import yaml

from benchmarks.results_file import machine, write_results
from design.api import solve
from design.solvers.optimize.pattern_search import LATTICE

ROOT = Path(__file__).resolve().parents[1]
RESULTS = Path(__file__).parent / "results" / "lattice.json"
PROBLEM = ROOT / "problems" / "hold_time.yaml"
LATTICES = (16, 32, LATTICE)


def run(lattice: int) -> dict:
    """The main job on a lattice of ``lattice`` units: its verified hold,
    design, simulations and wall time."""
    spec = yaml.safe_load(PROBLEM.read_text())
    spec["scene"] = str(PROBLEM.parent / spec["scene"])
    spec["solver"] = {**spec["solver"], "lattice": lattice}
    t0 = time.perf_counter()
    with tempfile.TemporaryDirectory() as out:
        result = solve(spec, out=out).to_dict()
    wall = time.perf_counter() - t0
    search = result["solver"]["search"]
    return {"lattice": lattice, "status": result["status"], "wall_time_s": wall,
            "simulations": search["simulations"], "same_runs": search["same_runs"],
            "lattice_optimum": search["lattice_optimum"],
            "verified_hold_time_s": result["verification"]["hold_time_s"],
            "verified_max_finger_force_N": result["verification"]["max_finger_force_N"],
            "cap_N": result["verification"]["cap_N"],
            "baseline_hold_time_s": result["baseline"]["hold_time_s"],
            "design": {v["name"]: v["optimum"] for v in result["variables"]}}


def main() -> None:
    load = os.getloadavg()
    rows = []
    for lattice in LATTICES:
        rows.append(run(lattice))
        r = rows[-1]
        print(f"lattice {lattice}: {r['status']}, verified hold {r['verified_hold_time_s']:.4f} "
              f"s, {r['simulations']} simulations, {r['wall_time_s']:.1f} s", flush=True)
    ref = next(r for r in rows if r["lattice"] == LATTICE)
    for r in rows:
        r["wall_over_default"] = r["wall_time_s"] / ref["wall_time_s"]
        r["hold_over_default"] = r["verified_hold_time_s"] / ref["verified_hold_time_s"]
        r["hold_over_baseline"] = r["verified_hold_time_s"] / r["baseline_hold_time_s"]
    default = f"/ {LATTICE}"
    print(f"\n{'lattice':>7s} {'finest step':>11s} {'sims':>5s} {'wall (s)':>8s} "
          f"{default:>6s} {'verified hold (s)':>17s} {default:>6s} {'/ baseline':>10s} "
          f"{'peak (N)':>8s}")
    for r in rows:
        print(f"{r['lattice']:7d} {1 / r['lattice']:11.5f} {r['simulations']:5d} "
              f"{r['wall_time_s']:8.1f} {r['wall_over_default']:6.3f} "
              f"{r['verified_hold_time_s']:17.5f} {r['hold_over_default']:6.3f} "
              f"{r['hold_over_baseline']:10.3f} {r['verified_max_finger_force_N']:8.2f}")
    write_results(RESULTS, {
        "machine": machine(load, at_end=True),
        "command": f"design solve {PROBLEM.relative_to(ROOT)} with solver.lattice "
                   f"{', '.join(map(str, LATTICES))} (design.api.solve, one after the other)",
        "default_lattice": LATTICE, "rows": rows})


if __name__ == "__main__":
    main()
