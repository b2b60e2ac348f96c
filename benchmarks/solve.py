"""The design NLP: how its cost grows with the time grid and the finger mesh.

For problems/hold_time.yaml (mean bird of Table 5-3, 8 variables) at
three (time step, beam intervals) sizes: the NLP built around the baseline's
simulated schedule with the first trust region (half-width 0.15), its size
(variables, constraints, Jacobian nonzeros, finger-contact stages), the
cost of one constraint evaluation and one exact constraint Jacobian, and one
Ipopt solve (iterations, wall time, status, hold time against the
re-simulated candidate). The simultaneous alternative, every finger stage's
collocation unknowns as NLP variables instead of embedded rootfinders, is
sized (not solved) for comparison.

Baseline a user would otherwise use: derivatives of the simulated hold time
by central differences over the forward simulator (2 n simulations for n
variables, as the thesis's one-at-a-time sweeps do), in the same run; the
ratio is the exact NLP Jacobian's cost over that.

Prints a table and writes benchmarks/results/solve.json.

    python benchmarks/solve.py
"""

from __future__ import annotations

import json
import os
import platform
import time
from dataclasses import replace
from pathlib import Path

import casadi as ca
import numpy as np

from design.api import check
from design.io.results import jsonable
from design.run.solve import design_space
from design.solve.optimize.schedule import schedule_of
from design.solve.optimize.transcription import DesignNLP
from design.solve.optimize.trust_region import simulate

ROOT = Path(__file__).resolve().parents[1]
RESULTS = Path(__file__).parent / "results" / "solve.json"
SIZES = [(0.01, 4), (0.005, 6), (0.0025, 8)]
RADIUS = 0.15


def timed(fn, repeat: int = 3) -> float:
    fn()
    t0 = time.perf_counter()
    for _ in range(repeat):
        fn()
    return (time.perf_counter() - t0) / repeat


def main() -> None:
    problem = check(ROOT / "problems" / "hold_time.yaml")
    space = design_space(problem)
    d0 = space.scale(space.base_values)
    box = (np.clip(d0 - RADIUS, 0, 1), np.clip(d0 + RADIUS, 0, 1))
    rows = []
    for step, beam in SIZES:
        nlp_settings = replace(problem.settings.nlp, time_step=step, beam_intervals=beam)
        settings = replace(problem.settings, nlp=nlp_settings, contact_nodes=beam)
        t0 = time.perf_counter()
        base = simulate(space, d0, settings)
        sim_time = time.perf_counter() - t0
        t0 = time.perf_counter()
        nlp = DesignNLP(space, schedule_of(base.run, step), base.run, base.peak,
                        nlp_settings, problem.rules, box)
        build = time.perf_counter() - t0
        jac = ca.Function("constraint_jacobian", [nlp.x], [ca.jacobian(nlp.g, nlp.x)])
        t_eval = timed(lambda: nlp.functions(nlp.x0))
        t_jac = timed(lambda: jac(nlp.x0), repeat=1)
        result = nlp.solve()
        candidate = simulate(space, result.d, settings)
        fd_gradient = 2 * space.size * sim_time
        size = nlp.size
        stages = size["finger_stages"]
        n_z = next(iter(nlp.fingers.values())).n_z["interior"] if nlp.fingers else 0
        rows.append({
            "time_step_s": step, "beam_intervals": beam, **size,
            "simultaneous_variables": size["variables"] + stages * n_z,
            "simultaneous_constraints": size["constraints"] + stages * n_z,
            "build_s": build, "constraint_eval_s": t_eval, "jacobian_eval_s": t_jac,
            "ipopt_status": result.status, "ipopt_iterations": result.iterations,
            "ipopt_wall_s": result.wall_time, "nlp_hold_s": result.hold_time,
            "simulated_hold_s": candidate.hold, "baseline_hold_s": base.hold,
            "simulation_s": sim_time, "fd_gradient_by_simulation_s": fd_gradient,
            "jacobian_over_fd_gradient": t_jac / fd_gradient})
        r = rows[-1]
        print(f"step {step * 1e3:4.1f} ms, beam {beam}: {r['variables']} vars, "
              f"{r['constraints']} cons, {r['jacobian_nonzeros']} nnz, {stages} finger stages; "
              f"eval {t_eval * 1e3:.0f} ms, Jacobian {t_jac:.2f} s "
              f"({r['jacobian_over_fd_gradient']:.3f} x an FD gradient by simulation); "
              f"Ipopt {result.status} {result.iterations} it {result.wall_time:.1f} s; hold NLP "
              f"{result.hold_time:.4f} s, simulated {candidate.hold:.4f} s "
              f"(baseline {base.hold:.4f} s)", flush=True)
    RESULTS.parent.mkdir(exist_ok=True)
    RESULTS.write_text(json.dumps(jsonable({
        "machine": {"cpus": os.cpu_count(), "python": platform.python_version()},
        "problem": "problems/hold_time.yaml", "trust_region": RADIUS, "rows": rows}),
        indent=1) + "\n")
    print(RESULTS)


if __name__ == "__main__":
    main()
