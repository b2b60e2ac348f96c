"""The design NLP: how its cost grows with the time grid and the finger mesh.

For problems/hold_time.yaml (mean bird of Table 5-3, 8 variables) at
three (time step, beam intervals) sizes: the NLP built around the baseline's
simulated schedule with the first trust region (half-width 0.15), its size
(variables, constraints, Jacobian nonzeros, finger-contact stages), the
cost of one constraint evaluation and one exact constraint Jacobian, and one
Ipopt solve (iterations, wall time, return status, hold time against the
re-simulated candidate). The simultaneous alternative, every finger stage's
collocation unknowns as NLP variables instead of embedded rootfinders, is
sized (not solved) for comparison.

Baseline a user would otherwise use, measured in the same run: the gradient
of the simulated hold time by central differences over the forward
simulator (2 n simulations for n variables, as the thesis's one-at-a-time
sweeps do). Two of those simulations are run, d0 ± h along the first
variable whose baseline lies inside its bounds (the first two sit on a
bound: a central difference there would repeat the baseline), and the
gradient's cost is 2 n times their mean; a simulation that does not end ok
is recorded and marked, and left out of the mean.

Like is compared with like, and the ratio says which:

* warm: one exact Jacobian evaluation once its CasADi function exists (best
  of three calls) against 2 n simulations each made after the first
  simulation of the run (the grasp simulator's CasADi functions built);
* cold: building the NLP and its Jacobian function plus the first Jacobian
  call, against the first simulation (which builds the simulator's
  functions) plus 2 n - 1 warm ones.

The one-off costs are reported separately (NLP build, Jacobian build and
first call, first simulation). Ipopt's wall time is the solve alone; building
the nlpsol and evaluating the result are given beside it. Each Ipopt row
records its return status and is marked when that is not a success
(``Solve_Succeeded`` or ``Solved_To_Acceptable_Level``): the problem caps each
NLP at ``max_iter`` iterations, because the design loop takes the iterate of
a trust region and re-simulates it, so ``Maximum_Iterations_Exceeded`` is the
expected outcome here, not a converged optimum.

Prints a table and writes benchmarks/results/solve.json.

Where the main job's time goes (issue 13): the whole ``design solve
problems/hold_time.yaml`` through the public API (``design.api.solve``), its
profile (wall time per phase, each CasADi function's evaluation time and
calls, Ipopt's own time, peak memory: design/solve/optimize/profile.py)
printed as a table and written to solve.json's ``main_job``, with its
status, verified and optimiser hold, and the machine's cores and load at
the start and end. About 1.5 minutes on 2 cores (4-5 before the compiled
contact functions of issue 13), on top of the sizes' 2.5.

    python -m benchmarks.solve                  # sizes, then the main job's profile
    python -m benchmarks.solve --profile-only   # the main job's profile only
    python -m benchmarks.solve --sizes-only     # the sizes only

Each mode keeps the other's section of solve.json as it was.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import time
from dataclasses import replace
from pathlib import Path

import casadi as ca
import numpy as np

from design.api import check, solve
from design.io.results import jsonable
from design.run.solve import design_space
from design.solve.optimize.profile import profile_text
from design.solve.optimize.schedule import schedule_of
from design.solve.optimize.transcription import DesignNLP, NLPFailed
from design.solve.optimize.trust_region import simulate

ROOT = Path(__file__).resolve().parents[1]
RESULTS = Path(__file__).parent / "results" / "solve.json"
SIZES = [(0.01, 4), (0.005, 6), (0.0025, 8)]
RADIUS = 0.15
#: central-difference step in the scaled design variable (0..1)
FD_STEP = 1e-3
#: Ipopt's return statuses that are a success
IPOPT_SUCCESS = ("Solve_Succeeded", "Solved_To_Acceptable_Level")


def clock(fn):
    """(result, wall time in s) of one call."""
    t0 = time.perf_counter()
    out = fn()
    return out, time.perf_counter() - t0


def best_of(fn, repeat: int = 3) -> float:
    """Best wall time (s) of ``repeat`` calls (call it warm: after a first one)."""
    return min(clock(fn)[1] for _ in range(repeat))


def fd_variable(d0: np.ndarray) -> int:
    """The first scaled variable a central difference of FD_STEP keeps in [0, 1]."""
    return next(k for k, v in enumerate(d0) if FD_STEP <= v <= 1.0 - FD_STEP)


def measure(problem, space, d0, box, step: float, beam: int) -> dict:
    nlp_settings = replace(problem.settings.nlp, time_step=step, beam_intervals=beam)
    settings = replace(problem.settings, nlp=nlp_settings, contact_nodes=beam)
    n = space.size

    # the baseline: simulations, the first cold, then two warm ones (d0 ± h e_k)
    base, sim_cold = clock(lambda: simulate(space, d0, settings))
    k = fd_variable(d0)
    sims = []
    for sign in (1.0, -1.0):
        d = d0.copy()
        d[k] += sign * FD_STEP
        run, dt = clock(lambda: simulate(space, d, settings))
        sims.append({"d": d[k], "hold_s": run.hold, "wall_s": dt, "ok": run.run.trajectory.ok,
                     "message": run.run.trajectory.message})
    warm = [x["wall_s"] for x in sims if x["ok"]]
    sim_warm = float(np.mean(warm)) if warm else float("nan")
    fd_warm = 2 * n * sim_warm
    fd_cold = sim_cold + (2 * n - 1) * sim_warm

    # the NLP: build, Jacobian function, first and warm evaluations
    nlp, nlp_build = clock(lambda: DesignNLP(space, schedule_of(base.run, step), base.run,
                                             base.peak, nlp_settings, problem.rules, box))
    jac, jac_build = clock(lambda: ca.Function("constraint_jacobian", [nlp.x],
                                               [ca.jacobian(nlp.g, nlp.x)]))
    _, jac_first = clock(lambda: jac(nlp.x0))
    jac_warm = best_of(lambda: jac(nlp.x0))
    _, eval_first = clock(lambda: nlp.functions(nlp.x0))
    eval_warm = best_of(lambda: nlp.functions(nlp.x0))
    jac_cold = nlp_build + jac_build + jac_first

    # one Ipopt solve: its status, whatever it is
    try:
        result, solve_call = clock(nlp.solve)
        status, success = result.status, result.status in IPOPT_SUCCESS
        ipopt = {"ipopt_iterations": result.iterations, "ipopt_wall_s": result.wall_time,
                 "ipopt_build_and_post_s": solve_call - result.wall_time,
                 "nlp_hold_s": result.hold_time,
                 "simulated_hold_s": simulate(space, result.d, settings).hold}
    except NLPFailed as exc:
        status, success = f"NLPFailed: {exc}", False
        ipopt = {"ipopt_iterations": None, "ipopt_wall_s": None, "ipopt_build_and_post_s": None,
                 "nlp_hold_s": None, "simulated_hold_s": None}

    size = nlp.size
    stages = size["finger_stages"]
    n_z = next(iter(nlp.fingers.values())).n_z["interior"] if nlp.fingers else 0
    return {
        "time_step_s": step, "beam_intervals": beam, **size,
        "simultaneous_variables": size["variables"] + stages * n_z,
        "simultaneous_constraints": size["constraints"] + stages * n_z,
        "nlp_build_s": nlp_build, "jacobian_build_s": jac_build,
        "jacobian_first_call_s": jac_first, "jacobian_eval_warm_s": jac_warm,
        "constraint_eval_first_s": eval_first, "constraint_eval_warm_s": eval_warm,
        "simulation_first_s": sim_cold, "simulation_warm_s": sim_warm,
        "fd_variable": space.variables[k].name, "fd_step": FD_STEP, "fd_simulations": sims,
        "fd_simulations_ok": all(x["ok"] for x in sims),
        "fd_gradient_warm_s": fd_warm, "fd_gradient_cold_s": fd_cold,
        "jacobian_over_fd_gradient_warm": jac_warm / fd_warm,
        "jacobian_over_fd_gradient_cold": jac_cold / fd_cold,
        "ipopt_status": status, "ipopt_success": success,
        "ipopt_max_iter": nlp_settings.max_iter, **ipopt,
        "baseline_hold_s": base.hold}


def fmt(value, spec: str) -> str:
    return "-" if value is None else format(value, spec)


def print_table(rows: list[dict]) -> None:
    print("\nsizes and derivative cost (warm: functions built; cold: building included)")
    print(f"{'step ms':>7} {'beam':>4} {'vars':>5} {'cons':>5} {'nnz':>6} {'stages':>6} "
          f"{'NLP build':>9} {'Jac build':>9} {'Jac warm':>8} {'sim 1st':>7} {'sim warm':>8} "
          f"{'FD warm':>7} {'warm x':>7} {'cold x':>7}")
    for r in rows:
        print(f"{r['time_step_s'] * 1e3:7.1f} {r['beam_intervals']:4d} {r['variables']:5d} "
              f"{r['constraints']:5d} {r['jacobian_nonzeros']:6d} {r['finger_stages']:6d} "
              f"{r['nlp_build_s']:8.2f}s "
              f"{r['jacobian_build_s'] + r['jacobian_first_call_s']:8.2f}s "
              f"{r['jacobian_eval_warm_s']:7.3f}s {r['simulation_first_s']:6.2f}s "
              f"{r['simulation_warm_s']:7.2f}s {r['fd_gradient_warm_s']:6.1f}s "
              f"{r['jacobian_over_fd_gradient_warm']:7.4f} "
              f"{r['jacobian_over_fd_gradient_cold']:7.4f}"
              f"{'' if r['fd_simulations_ok'] else '  <- an FD simulation failed'}")
    print(f"  warm x: one warm exact Jacobian over a warm central-difference gradient "
          f"(2n simulations, timed along {rows[0]['fd_variable']}); cold x: NLP + Jacobian "
          "build + first call over the first simulation + 2n-1 warm ones")
    for r in rows:
        for x in r["fd_simulations"]:
            if not x["ok"]:
                print(f"  {r['time_step_s'] * 1e3:.1f} ms: the simulation at {r['fd_variable']} "
                      f"= {x['d']:.4f} (scaled) failed: {x['message']}")
    print("\nIpopt, one NLP per size (the problem's max_iter per NLP)")
    print(f"{'step ms':>7} {'beam':>4} {'status':34} {'it':>4} {'wall':>7} {'build+post':>10} "
          f"{'hold NLP':>9} {'simulated':>9} {'baseline':>9}")
    for r in rows:
        mark = "" if r["ipopt_success"] else "  <- not a success"
        print(f"{r['time_step_s'] * 1e3:7.1f} {r['beam_intervals']:4d} {r['ipopt_status']:34} "
              f"{fmt(r['ipopt_iterations'], '4d')} {fmt(r['ipopt_wall_s'], '6.1f')}s "
              f"{fmt(r['ipopt_build_and_post_s'], '9.1f')}s {fmt(r['nlp_hold_s'], '9.4f')} "
              f"{fmt(r['simulated_hold_s'], '9.4f')} {r['baseline_hold_s']:9.4f}{mark}")
    capped = [r for r in rows if r["ipopt_status"] == "Maximum_Iterations_Exceeded"]
    if capped:
        print(f"  {len(capped)} of {len(rows)} stopped at max_iter = {capped[0]['ipopt_max_iter']}: "
              "an iterate of the trust region, not a converged optimum")


def main_job() -> dict:
    """``design solve problems/hold_time.yaml`` through the public API: its
    outcome and profile, printed as a table."""
    load = os.getloadavg()
    t0 = time.perf_counter()
    result = solve(ROOT / "problems" / "hold_time.yaml",
                   progress=lambda message: print(f"  {message}", flush=True))
    wall = time.perf_counter() - t0
    v = result["verification"]
    print(f"\nmain job: {result['status']}; verified hold {v['hold_time_s']:.4f} s (optimiser "
          f"{result['objective']['hold_time_s']:.4f} s, baseline "
          f"{result['baseline']['hold_time_s']:.4f} s), peak {v['max_finger_force_N']:.2f} N "
          f"(cap {v['cap_N']:.2f} N); {wall:.1f} s through the API")
    print("\nwhere the main job's time went")
    print(profile_text(result["profile"]))
    return {"command": "design solve problems/hold_time.yaml (design.api.solve)",
            "status": result["status"], "verified_hold_time_s": v["hold_time_s"],
            "optimiser_hold_time_s": result["objective"]["hold_time_s"],
            "baseline_hold_time_s": result["baseline"]["hold_time_s"],
            "max_finger_force_N": v["max_finger_force_N"], "cap_N": v["cap_N"],
            "ipopt_iterations": result["solver"]["iterations"],
            "outer_iterations": result["solver"]["outer_iterations"],
            "api_wall_time_s": wall, "load_average_at_start": load,
            "load_average_at_end": os.getloadavg(), "profile": result["profile"]}


def sizes() -> dict:
    """The NLP's cost at three sizes against the FD gradient (the module's
    first table)."""
    load = os.getloadavg()
    problem = check(ROOT / "problems" / "hold_time.yaml")
    space = design_space(problem)
    d0 = space.scale(space.base_values)
    box = (np.clip(d0 - RADIUS, 0, 1), np.clip(d0 + RADIUS, 0, 1))
    rows = []
    for step, beam in SIZES:
        rows.append(measure(problem, space, d0, box, step, beam))
        r = rows[-1]
        print(f"step {step * 1e3:4.1f} ms, beam {beam}: Jacobian {r['jacobian_eval_warm_s']:.3f} s "
              f"warm, {r['jacobian_over_fd_gradient_warm']:.4f} x a warm FD gradient; Ipopt "
              f"{r['ipopt_status']}{'' if r['ipopt_success'] else ' (not a success)'}",
              flush=True)
    print_table(rows)
    return {"machine": {"cpus": os.cpu_count(), "python": platform.python_version(),
                        "load_average_at_start": load, "load_average_at_end": os.getloadavg()},
            "problem": "problems/hold_time.yaml", "trust_region": RADIUS,
            "comparison": "warm against warm (jacobian_over_fd_gradient_warm) and cold against "
                          "cold (jacobian_over_fd_gradient_cold); build times separate",
            "ipopt_success_statuses": list(IPOPT_SUCCESS), "rows": rows}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    only = parser.add_mutually_exclusive_group()
    only.add_argument("--profile-only", action="store_true",
                      help="run the main job and record its profile only")
    only.add_argument("--sizes-only", action="store_true",
                      help="the NLP sizes and derivative costs only")
    args = parser.parse_args()
    old = json.loads(RESULTS.read_text()) if RESULTS.exists() else {}
    data = dict(old) if args.profile_only else sizes()
    if not args.sizes_only:
        data["main_job"] = main_job()
    elif "main_job" in old:
        data["main_job"] = old["main_job"]
    RESULTS.parent.mkdir(exist_ok=True)
    RESULTS.write_text(json.dumps(jsonable(data), indent=1) + "\n")
    print(RESULTS)


if __name__ == "__main__":
    main()
