"""The design NLP: how its cost grows with the time grid and the finger mesh.

For problems/hold_time.yaml (mean bird of Table 5-3, 8 variables) at
3 x 3 sizes, every pair of a time step of 10, 5 or 2.5 ms and a finger mesh
of 4, 6 or 8 beam intervals: the NLP built around the baseline's simulated
schedule with the first trust region (half-width 0.15), its size
(variables, constraints, Jacobian nonzeros, finger-contact stages), the
cost of one constraint evaluation and one exact constraint Jacobian, and one
Ipopt solve (iterations, wall time, return status, hold time against the
re-simulated candidate). The simultaneous alternative, every finger stage's
collocation unknowns as NLP variables instead of embedded rootfinders, is
sized (not solved) for comparison.

Memory: each size runs in its own fresh process
(multiprocessing's "spawn"), one after the other, never two at once, so its
resident set is its own. A row records the resident set just before the NLP
is built (after the simulations: Python, CasADi, the simulator), the peak
resident set (``ru_maxrss``) after the Ipopt solve, their difference as the
NLP's own memory (build, Jacobian, evaluations and Ipopt; marked as an upper
bound when the NLP stayed below a peak the simulations had set), and the
process's peak at the end. The simulator's functions are built in each
process as a run would build them; compiled functions come from the on-disk
compile cache (the first run on an empty cache compiles them, and its NLP
builds are seconds longer).

How the cost grows: after the tables, a least-squares fit of
log(cost) = a + b log(stages) over the 9 rows (each row's finger stages) for
the Jacobian and constraint evaluations, Ipopt's wall time per iteration,
the NLP build and the NLP's memory, printed one line each ("Jacobian
evaluation grows as stages^b", b = 1 linear) and written to solve.json's
``growth`` and ``growth_summary``; beside it a fit with log(beam intervals)
as a second regressor, since the 3 meshes at one time step share their
stage count and the mesh's share would otherwise be noise in the first fit.

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
  of at least three calls, more up to 1 s of calls) against 2 n simulations each made after the first
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

Prints the tables and writes benchmarks/results/solve.json.

Where the main job's time goes: the whole ``design solve
problems/hold_time.yaml`` through the public API (``design.api.solve``), its
profile (wall time per phase, each CasADi function's evaluation time and
calls, Ipopt's own time, peak memory: design/solvers/optimize/profile.py)
printed as a table and written to solve.json's ``main_job``, with its
status, verified and optimiser hold, and the machine's cores and load at
the start and end; the sizes record their wall time and the load averages
at their start and end too.

    python -m benchmarks.solve                  # sizes, then the main job's profile
    python -m benchmarks.solve --profile-only   # the main job's profile only
    python -m benchmarks.solve --sizes-only     # the sizes only

Each mode keeps the other's section of solve.json as it was.
"""

from __future__ import annotations

import argparse
import json
import multiprocessing
import os
import resource
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import replace
from datetime import datetime, timezone
from pathlib import Path

import casadi as ca
import numpy as np

from benchmarks.results_file import cpu_model, machine, write_results
from design.api import check, solve
from design.run.solve import design_space
from design.solvers.optimize.profile import profile_text
from design.solvers.optimize.schedule import schedule_of
from design.solvers.optimize.transcription import DesignNLP, NLPFailed
from design.solvers.optimize.trust_region import simulate

ROOT = Path(__file__).resolve().parents[1]
RESULTS = Path(__file__).parent / "results" / "solve.json"
#: the time steps (s) and beam intervals measured: every pair, coarsest first
TIME_STEPS = (0.01, 0.005, 0.0025)
BEAM_INTERVALS = (4, 6, 8)
SIZES = [(step, beam) for step in TIME_STEPS for beam in BEAM_INTERVALS]
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


def best_of(fn, repeat: int = 3, budget: float = 1.0, most: int = 100) -> float:
    """Best wall time (s) of at least ``repeat`` calls, more while they take
    less than ``budget`` s together (at most ``most``): a call of a few ms is
    timed often enough that another job's slice of the core does not decide
    its best (call it warm: after a first one)."""
    times = []
    while len(times) < repeat or (sum(times) < budget and len(times) < most):
        times.append(clock(fn)[1])
    return min(times)


def rss_mib() -> float:
    """This process's resident set size now (MiB; Linux's /proc/self/status)."""
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) / 1024
    return float("nan")


def peak_rss_mib() -> float:
    """This process's peak resident set size since it started (MiB; ru_maxrss
    is in KiB on Linux)."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


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
    rss_before, peak_before = rss_mib(), peak_rss_mib()
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
        peak_nlp = peak_rss_mib()
        status, success = result.status, result.status in IPOPT_SUCCESS
        ipopt = {"ipopt_iterations": result.iterations, "ipopt_wall_s": result.wall_time,
                 "ipopt_build_and_post_s": solve_call - result.wall_time,
                 "nlp_hold_s": result.hold_time,
                 "simulated_hold_s": simulate(space, result.d, settings).hold}
    except NLPFailed as exc:
        peak_nlp = peak_rss_mib()
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
        "baseline_hold_s": base.hold,
        "rss_before_nlp_mib": rss_before, "peak_rss_before_nlp_mib": peak_before,
        "peak_rss_after_ipopt_mib": peak_nlp,
        "nlp_memory_mib": peak_nlp - rss_before,
        "nlp_raised_peak": peak_nlp > peak_before}


def measure_row(step: float, beam: int) -> dict:
    """One row of the sizes table, run in a fresh process (``sizes`` spawns one
    per row): the problem loaded, ``measure`` at (step, beam), and the
    process's peak resident set at the end."""
    t0 = time.perf_counter()
    rss_start = rss_mib()
    problem = check(ROOT / "problems" / "hold_time.yaml").value
    space = design_space(problem)
    d0 = space.scale(space.base_values)
    box = (np.clip(d0 - RADIUS, 0, 1), np.clip(d0 + RADIUS, 0, 1))
    row = measure(problem, space, d0, box, step, beam)
    return {**row, "rss_child_start_mib": rss_start, "peak_rss_mib": peak_rss_mib(),
            "child_wall_s": time.perf_counter() - t0}


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


#: the costs whose growth with the finger stages is fitted: (key, label, cost of a row)
GROWTH = (
    ("jacobian_eval", "Jacobian evaluation", lambda r: r["jacobian_eval_warm_s"]),
    ("constraint_eval", "constraint evaluation", lambda r: r["constraint_eval_warm_s"]),
    ("ipopt_per_iteration", "Ipopt wall time per iteration",
     lambda r: (r["ipopt_wall_s"] / r["ipopt_iterations"]
                if r["ipopt_wall_s"] is not None and r["ipopt_iterations"] else None)),
    ("nlp_build", "NLP build", lambda r: r["nlp_build_s"]),
    ("nlp_memory", "NLP memory", lambda r: r["nlp_memory_mib"]),
)


def growth(rows: list[dict]) -> dict:
    """Least-squares fits of log(cost) = a + b log(stages) over the rows
    (``finger_stages`` of each row; rows without a positive cost left out),
    and, beside it, log(cost) = a + b log(stages) + c log(beam intervals),
    which separates the finger mesh's share from the grid's."""
    out = {}
    for key, label, cost in GROWTH:
        pts = [(r["finger_stages"], r["beam_intervals"], cost(r)) for r in rows]
        pts = [(s, m, c) for s, m, c in pts if c is not None and c > 0]
        counts = [s for s, _, _ in pts]
        stages, beams, costs = (np.log(np.array(v, dtype=float)) for v in zip(*pts))
        a = np.column_stack([np.ones_like(stages), stages])
        coef, *_ = np.linalg.lstsq(a, costs, rcond=None)
        fitted = a @ coef
        spread = np.sum((costs - costs.mean()) ** 2)
        r2 = 1 - np.sum((costs - fitted) ** 2) / spread if spread > 0 else float("nan")
        coef2, *_ = np.linalg.lstsq(np.column_stack([a, beams]), costs, rcond=None)
        out[key] = {"label": label, "exponent": float(coef[1]), "log_intercept": float(coef[0]),
                    "r_squared": float(r2), "rows": len(pts),
                    "stages_min": min(counts), "stages_max": max(counts),
                    "with_beam": {"stages_exponent": float(coef2[1]),
                                  "beam_exponent": float(coef2[2])}}
    return out


def growth_lines(fits: dict) -> list[str]:
    return [f"{f['label']} grows as stages^{f['exponent']:.2f} (stages {f['stages_min']}-"
            f"{f['stages_max']}, {f['rows']} rows, R^2 {f['r_squared']:.2f}; with the beam "
            f"separated: stages^{f['with_beam']['stages_exponent']:.2f} x "
            f"beam^{f['with_beam']['beam_exponent']:.2f})" for f in fits.values()]


def print_cost_table(rows: list[dict]) -> None:
    print("\ncost growth: one fresh process per row (memory: NLP = peak during the NLP's "
          "build, evaluations and Ipopt minus the RSS just before its build; peak = the "
          "process's)")
    print(f"{'step ms':>7} {'beam':>4} {'stages':>6} {'vars':>5} {'cons':>5} {'nnz':>6} "
          f"{'g ms':>7} {'jac ms':>7} {'it':>4} {'status':28} {'Ipopt s':>7} {'build s':>7} "
          f"{'RSS0':>6} {'NLP MiB':>7} {'peak':>6}")
    for r in rows:
        print(f"{r['time_step_s'] * 1e3:7.1f} {r['beam_intervals']:4d} {r['finger_stages']:6d} "
              f"{r['variables']:5d} {r['constraints']:5d} {r['jacobian_nonzeros']:6d} "
              f"{r['constraint_eval_warm_s'] * 1e3:7.1f} {r['jacobian_eval_warm_s'] * 1e3:7.1f} "
              f"{fmt(r['ipopt_iterations'], '4d')} {r['ipopt_status'][:28]:28} "
              f"{fmt(r['ipopt_wall_s'], '7.2f')} {r['nlp_build_s']:7.2f} "
              f"{r['rss_before_nlp_mib']:6.0f} {r['nlp_memory_mib']:7.1f} "
              f"{r['peak_rss_mib']:6.0f}"
              f"{'' if r['nlp_raised_peak'] else '  <- NLP below an earlier peak'}")


def main_job() -> dict:
    """``design solve problems/hold_time.yaml`` through the public API, its
    files written where the command writes them (reports/hold_time: the
    README's screenshots come from its report): its outcome and profile,
    printed as a table."""
    load = os.getloadavg()
    t0 = time.perf_counter()
    result = solve(ROOT / "problems" / "hold_time.yaml", out=ROOT / "reports" / "hold_time",
                   progress=lambda message: print(f"  {message}", flush=True)).to_dict()
    wall = time.perf_counter() - t0
    v = result["verification"]
    print(f"\nmain job: {result['status']}; verified hold {v['hold_time_s']:.4f} s (optimiser "
          f"{result['objective']['hold_time_s']:.4f} s, baseline "
          f"{result['baseline']['hold_time_s']:.4f} s), peak {v['max_finger_force_N']:.2f} N "
          f"(cap {v['cap_N']:.2f} N); {wall:.1f} s through the API")
    print("\nwhere the main job's time went")
    print(profile_text(result["profile"]))
    return {"command": "design solve problems/hold_time.yaml (design.api.solve)",
            "measured_at": datetime.now(timezone.utc).date().isoformat(),
            "status": result["status"], "verified_hold_time_s": v["hold_time_s"],
            "optimiser_hold_time_s": result["objective"]["hold_time_s"],
            "baseline_hold_time_s": result["baseline"]["hold_time_s"],
            "max_finger_force_N": v["max_finger_force_N"], "cap_N": v["cap_N"],
            "method": result["solver"]["method"],
            "simulations": (result["solver"]["search"] or {}).get("simulations"),
            "search_processes_cpu_time_s":
                (result["solver"]["search"] or {}).get("processes_cpu_time_s"),
            "ipopt_iterations": result["solver"]["iterations"],
            "outer_iterations": result["solver"]["outer_iterations"],
            "robustness": None if not result.get("robustness") else {
                "share_beaten": result["robustness"]["share_beaten"],
                "not_beaten": {r["case"]: r["why_not"] for r in result["robustness"]["cases"]
                               if not r["optimum_beats_baseline"]}},
            "api_wall_time_s": wall, "cpu": cpu_model(), "load_average_at_start": load,
            "load_average_at_end": os.getloadavg(), "profile": result["profile"]}


def sizes() -> dict:
    """The NLP's cost at the 3 x 3 sizes against the FD gradient, and how it
    grows with the finger stages (the module's first tables). Each row runs in
    its own fresh (spawned) process, one after the other, so its memory is
    its own."""
    load = os.getloadavg()
    t0 = time.perf_counter()
    context = multiprocessing.get_context("spawn")
    rows = []
    for step, beam in SIZES:
        with ProcessPoolExecutor(max_workers=1, mp_context=context) as child:
            rows.append(child.submit(measure_row, step, beam).result())
        r = rows[-1]
        print(f"step {step * 1e3:4.1f} ms, beam {beam}: {r['finger_stages']} stages, Jacobian "
              f"{r['jacobian_eval_warm_s']:.3f} s warm, "
              f"{r['jacobian_over_fd_gradient_warm']:.4f} x a warm FD gradient; Ipopt "
              f"{r['ipopt_status']}{'' if r['ipopt_success'] else ' (not a success)'}; NLP "
              f"{r['nlp_memory_mib']:.0f} MiB, peak {r['peak_rss_mib']:.0f} MiB; "
              f"{r['child_wall_s']:.0f} s", flush=True)
    wall = time.perf_counter() - t0
    print_table(rows)
    print_cost_table(rows)
    fits = growth(rows)
    print("\nhow the cost grows (least squares of log cost on log finger stages over the rows)")
    for line in growth_lines(fits):
        print(f"  {line}")
    end = os.getloadavg()
    print(f"\nsizes: {wall:.0f} s wall; load average {', '.join(f'{x:.2f}' for x in load)} at "
          f"the start, {', '.join(f'{x:.2f}' for x in end)} at the end ({os.cpu_count()} cores)")
    return {"machine": machine(load, at_end=True),
            "problem": "problems/hold_time.yaml", "trust_region": RADIUS,
            "wall_time_s": wall,
            "comparison": "warm against warm (jacobian_over_fd_gradient_warm) and cold against "
                          "cold (jacobian_over_fd_gradient_cold); build times separate",
            "memory": "each row in a fresh spawned process, one at a time; rss_before_nlp_mib: "
                      "its resident set just before the NLP is built (after the simulations); "
                      "peak_rss_after_ipopt_mib: its peak resident set (ru_maxrss) after the "
                      "Ipopt solve; nlp_memory_mib: the difference, the NLP's own share "
                      "(nlp_raised_peak false: the NLP stayed below a peak the simulations set, "
                      "so the share is an upper bound); peak_rss_mib: the process's peak at "
                      "the end",
            "ipopt_success_statuses": list(IPOPT_SUCCESS), "rows": rows,
            "growth": fits, "growth_summary": growth_lines(fits)}


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
    write_results(RESULTS, data)


if __name__ == "__main__":
    main()
