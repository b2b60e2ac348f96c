"""The planar contact solver on random valid poses, against an independent reference.

Poses from tests/problems.py::entering_poses (the object clear of the drum,
the straight finger entering it at 20-30 % of its length; the thesis's soft
finger). Each pose is solved with the side imposed (push, then pull; µ = 0
and 0.4 in turn) and compared with tests/contact_reference.py (least-energy
finger refined by solve_bvp) on that side; and, at µ = 0 and at 0.4, with
the side left to the solver, alone and as one sequence of all the poses
(each continued from the last, unrelated, one).

Prints a table and writes benchmarks/results/contact_poses.json (or
``--out``).

Times, warm against warm: the solver and the reference each solve the first
pose once before the timed loop (building their CasADi functions and
Ipopt's NLP); those first calls are reported apart, and the reference's time
per solve is given as a ratio to the solver's.

    python -m benchmarks.contact_poses              # 1000 poses, ~7 minutes
    python -m benchmarks.contact_poses --count 200 --out /tmp/poses.json
                                # (from the checkout root: it uses tests/ as a package)
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import time
from collections import Counter
from pathlib import Path

import numpy as np

from design.physics.contact import SIDES
from design.solvers.contact import RobustContact
from tests.contact_reference import reference
from tests.problems import entering_poses, thesis_finger

RESULTS = Path(__file__).parent / "results" / "contact_poses.json"
SEED = 2012


def run(count: int) -> dict:
    finger = thesis_finger()
    poses = entering_poses(SEED, count)
    solvers = {mu: RobustContact(finger, mu) for mu in (0.0, 0.4)}
    # first calls (cold): the CasADi functions and the reference's NLP are built here
    first = {}
    pose, ell = poses[0]
    for mu, solver in solvers.items():
        t0 = time.perf_counter()
        solver.solve(pose, ell, "push")
        first[f"solver_mu={mu:g}_s"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    reference(finger, pose.view(ell), 0.0, SIDES["push"])
    first["reference_s"] = time.perf_counter() - t0
    failures: Counter = Counter()
    imposed = {"solves": 0, "converged": 0, "no_equilibrium_on_side": 0,
               "said_other_side": 0, "bent_past_90_deg": 0, "max_point_error_m": 0.0,
               "max_force_error_rel": 0.0}
    solve_time = ref_time = 0.0
    for i, (pose, ell) in enumerate(poses):
        mu = (0.0, 0.4)[i % 2]
        for sliding in ("push", "pull"):
            t0 = time.perf_counter()
            sol = solvers[mu].solve(pose, ell, sliding)
            solve_time += time.perf_counter() - t0
            t0 = time.perf_counter()
            ref = reference(finger, pose.view(ell), mu, SIDES[sliding])
            ref_time += time.perf_counter() - t0
            imposed["solves"] += 1
            imposed["converged"] += sol.converged
            if not sol.converged:
                failures[sol.message.split(":")[0]] += 1
            if ref is None:
                imposed["no_equilibrium_on_side"] += 1
                imposed["said_other_side"] += "other side" in sol.message
            elif sol.converged:
                imposed["bent_past_90_deg"] += abs(sol.psi) > np.pi / 2
                imposed["max_point_error_m"] = max(imposed["max_point_error_m"], float(
                    np.hypot(*np.subtract(sol.point, ref.point))))
                imposed["max_force_error_rel"] = max(imposed["max_force_error_rel"], float(
                    abs(sol.force - ref.force) / ref.force))
    auto = {}
    for mu, solver in solvers.items():
        alone = [solver.solve(p, e, "auto") for p, e in poses]
        chained = solver.solve_pass([p for p, _ in poses], [e for _, e in poses], "auto")
        auto[f"mu={mu:g}"] = {"poses": count,
                              "alone_converged": sum(s.converged and s.contact for s in alone),
                              "sequence_converged": sum(s.converged and s.contact
                                                        for s in chained)}
    return {"machine": {"python": platform.python_version(), "cores": os.cpu_count()},
            "seed": SEED, "poses": count, "imposed_side": imposed,
            "imposed_side_failures_by_message": dict(failures), "auto_side": auto,
            "timing": "warm: after the first calls (first_call_s)", "first_call_s": first,
            "time_per_solve_s": solve_time / (2 * count),
            "reference_time_per_solve_s": ref_time / (2 * count),
            "reference_over_solver_time": ref_time / solve_time}


def print_table(result: dict) -> None:
    imp = result["imposed_side"]
    print(f"{result['poses']} poses (seed {result['seed']}), imposed side: "
          f"{imp['converged']} of {imp['solves']} converged; reference found none on the side "
          f"for {imp['no_equilibrium_on_side']} (solver said 'other side' for "
          f"{imp['said_other_side']}); max error against it {imp['max_point_error_m']:.1e} m, "
          f"{imp['max_force_error_rel']:.1e} in force")
    for message, n in result["imposed_side_failures_by_message"].items():
        print(f"  not converged: {n} x {message}")
    print(f"{'side left to the solver':24} {'poses':>6} {'alone':>6} {'sequence':>9}")
    for mu, a in result["auto_side"].items():
        print(f"{mu:24} {a['poses']:6d} {a['alone_converged']:6d} {a['sequence_converged']:9d}")
    print(f"time per solve (warm): solver {result['time_per_solve_s'] * 1e3:.1f} ms, reference "
          f"{result['reference_time_per_solve_s'] * 1e3:.1f} ms "
          f"({result['reference_over_solver_time']:.1f}x the solver); first calls: "
          + ", ".join(f"{k} {v:.2f} s" for k, v in result["first_call_s"].items()))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--count", type=int, default=1000)
    parser.add_argument("--out", type=Path, default=RESULTS,
                        help="JSON to write (default: benchmarks/results/contact_poses.json)")
    args = parser.parse_args()
    result = run(args.count)
    print_table(result)
    args.out.write_text(json.dumps(result, indent=1) + "\n")
    print(args.out)


if __name__ == "__main__":
    main()
