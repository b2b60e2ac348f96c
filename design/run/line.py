"""Running a line-speed problem (``objective: throughput``; ``design solve``).

Each number of finger sets n of the problem's ``finger_sets`` (by default the
grasper's own) is a case of the study: the grasper with n sets, the pattern
search raising the line's rate (design/solvers/optimize/line.py) from the
problem's design, and its answer verified bird by bird at 4x finer
resolution. A case's design keeps the rules when, in the verification,
every bird is under the cap (within its 1 %), no finger past its fold
force, no bird jammed, and every bird held at least ``min_hold`` (within the
verification's 2 % on the hold). The run's answer is the case with the
highest rate that keeps them (then the longest worst hold); what limits
it is what the nearest faster design the search simulated breaks (which
bird, which finger, which rule), or the drum speed's bound.

result.json's ``line`` has every case and the baseline; ``pareto`` the
designs the searches simulated that no other beats on all three of rate,
worst hold and peak force (jammed ones excluded); ``line_pareto.png``
draws them with the thesis's 60 and the kill line's 180 birds/min.
"""

from __future__ import annotations

import time
from dataclasses import replace
from functools import partial

import numpy as np

from design import __version__
from design.errors import StudyFailed
from design.io.design_problem import DesignProblem
from design.run import Progress, RunOutput
from design.run.grasp import timeseries
from design.run.solve import (VERIFIED, design_bird_peak, design_space,
                              population_of_problem, problem_digest)
from design.solvers.optimize.line import KILL_LINE_RATE, THESIS_RATE, broken, rate_of
from design.solvers.optimize.pattern_search import search
from design.solvers.optimize.population import Population
from design.solvers.optimize.trust_region import (CAP_TOLERANCE, HOLD_TOLERANCE, Scored,
                                                population_verdict, verify)
from design.solvers.optimize.variables import (DesignSpace, Variable, parameters_of,
                                             synchronised)
from design.solvers.reproducible import numerics, one_blas_thread
from design.study.cases import FAILED as CASE_FAILED
from design.study.cases import Case, StudyOptions
from design.study.engine import run_study
from design.study.progress import RATE, StudyProgress
from design.result import Status

#: a case's status when no design it simulated keeps the rules
NO_DESIGN = "no design keeps the rules"


def run(problem: DesignProblem, progress: Progress | None = None,
        study: StudyOptions | None = None) -> RunOutput:
    """The line-speed study (module docstring), every BLAS on one thread."""
    with one_blas_thread():
        return _run(problem, progress, study)


def _run(problem: DesignProblem, progress: Progress | None, study: StudyOptions | None
         ) -> RunOutput:
    t0 = time.perf_counter()
    say = progress or (lambda message: None)
    space = design_space(problem, progress)
    population = population_of_problem(problem, space)
    settings = problem.settings
    say(f"simulating the baseline at 4x the optimiser's resolution for "
        f"{len(population.members)} bird(s)")
    baseline = verify(population, space.scale(space.base_values), settings)
    cap = problem.caps[0].resolve(design_bird_peak(population, space, baseline, settings))
    own = space.baseline.grasper.sets
    cases = [Case(f"sets-{n}", {"sets": n, "cap_N": cap})
             for n in (problem.finger_sets or (own,))]
    options = study or StudyOptions(workers=1)
    if len(cases) == 1:
        options = replace(options, workers=1, scheduler=None)
    results = run_study(cases, partial(solve_sets, problem, progress if len(cases) == 1
                                       else None),
                        options=options, label=problem.name,
                        progress=None if len(cases) == 1 else
                        StudyProgress(quiet=progress is None, goal=RATE),
                        problem_digest=problem_digest(problem))
    failed = {k: r for k, r in results.items() if r["status"] in CASE_FAILED}
    if failed:
        raise StudyFailed("; ".join(f"case {k!r}: {r['status']}: {r.get('message', '')}"
                                    for k, r in failed.items()))
    return _output(problem, space, population, baseline, cap, results, t0)


def sets_population(problem: DesignProblem, n: int) -> tuple[DesignSpace, Population]:
    """The problem's design space and population with ``n`` finger sets, the
    bird meeting its set as in the scene (the variables' bounds as stated,
    their baseline values those of n sets)."""
    space = design_space(problem)
    if n == space.baseline.grasper.sets:
        return space, population_of_problem(problem, space)
    setup = synchronised(replace(space.baseline, grasper=space.baseline.grasper.with_sets(n)),
                         space.baseline)
    base = parameters_of(setup)
    space = DesignSpace(setup, [Variable(v.name, v.lo, v.hi, base[v.name])
                                for v in space.variables])
    population = population_of_problem(problem, space)
    return space, population


def solve_sets(problem: DesignProblem, progress: Progress | None, case: Case,
               upstream: dict | None) -> dict:
    """One case: the search with ``case.inputs["sets"]`` finger sets, its
    answer verified at 4x finer resolution (JSON)."""
    n, cap = case.inputs["sets"], case.inputs["cap_N"]
    space, population = sets_population(problem, n)
    settings = problem.settings
    outcome = search(population, cap, settings, problem.rules, progress=progress)
    fine = verify(population, outcome.best.d, settings)
    check = population_verdict(population, outcome.claims, fine, outcome.caps)
    kept = keeps_rules(fine, outcome.caps, problem.min_hold)
    searched_kept = keeps_rules(outcome.best, outcome.caps, problem.min_hold, tolerance=0.0)
    status = (VERIFIED if check["passed"] and kept else
              NO_DESIGN if not searched_kept else Status.FAILED_VERIFICATION)
    rate = rate_of(fine)
    return {"status": str(status), "sets": n, "line_rate_per_min": rate,
            "limit": faster_limit(outcome, problem.min_hold, space),
            "message": _case_message(status, n, rate, fine, problem.min_hold),
            "d": outcome.best.d.tolist(), "design": space.design(outcome.best.d),
            "line": line_of(space, outcome.best.d),
            "hold_time_s": fine.hold, "max_finger_force_N": fine.peak,
            "verified": status == VERIFIED, "verification": check,
            "birds": bird_rows(population, fine),
            "search": outcome.search, "wall_time_s": outcome.wall_time,
            "trials": [{"line_rate_per_min": t["line_rate_per_min"],
                        "hold_time_s": t["simulated_hold_time_s"],
                        "max_finger_force_N": t["simulated_peak_force_N"],
                        "keeps_limits": t["keeps_limits"], "jammed_birds": t["jammed_birds"],
                        "candidate_scaled": t["candidate_scaled"]}
                       for t in outcome.iterations]}


def keeps_rules(scored: Scored, caps, min_hold: float, tolerance: float = CAP_TOLERANCE
                ) -> bool:
    """Every bird under its cap and fold forces (within ``tolerance``), none
    jammed, each held ``min_hold`` (within the verification's hold
    tolerance where ``tolerance`` is the verification's)."""
    slack = HOLD_TOLERANCE if tolerance else 0.0
    return scored.within(caps, tolerance) and \
        float(scored.holds.min()) >= min_hold * (1 - slack)


def line_of(space: DesignSpace, d) -> dict:
    """The line of a scaled design: drum speed, belt speed, bird spacing (SI)."""
    values = space.values(np.asarray(d, float))
    return {"drum_speed_rad_s": float(values["drum_speed"]),
            "drum_speed_rpm": float(values["drum_speed"]) * 60 / (2 * np.pi),
            "belt_speed_m_s": float(values["conveyor.speed"]),
            "bird_spacing_m": float(values["bird_spacing"]),
            "finger_sets": space.baseline.grasper.sets}


def bird_rows(population: Population, scored: Scored) -> list[dict]:
    """Each bird's verified hold (s), peak (N) and jam (the reasons)."""
    return [{"bird": m.name, "hold_time_s": e.hold, "max_finger_force_N": e.peak,
             "max_finger_force_finger": e.run.summary["max_finger_force_finger"],
             "jam": "; ".join(e.run.summary["jam"])}
            for m, e in zip(population.members, scored.members)]


def _case_message(status, n: int, rate: float, fine: Scored, min_hold: float) -> str:
    limiting = fine.population.members[fine.limiting].name
    numbers = (f"{n} sets, {rate:.1f} birds/min: worst hold {fine.hold:.4f} s "
               f"({limiting}), peak {fine.peak:.2f} N")
    if status == VERIFIED:
        return f"verified at 4x finer resolution: {numbers}"
    if status == NO_DESIGN:
        return (f"no design the search simulated keeps every bird under the cap, unjammed "
                f"and held {min_hold:g} s; nearest: {numbers}")
    return f"the 4x finer simulation does not confirm the search's design: {numbers}"


def pareto(rows: list[dict]) -> list[dict]:
    """The rows no other row beats on all of rate (up), worst hold (up) and
    peak force (down), jammed designs and failed runs excluded."""
    pool = [r for r in rows if r["jammed_birds"] == 0 and np.isfinite(r["max_finger_force_N"])]

    def dominated(r):
        return any(o["line_rate_per_min"] >= r["line_rate_per_min"] and
                   o["hold_time_s"] >= r["hold_time_s"] and
                   o["max_finger_force_N"] <= r["max_finger_force_N"] and
                   (o["line_rate_per_min"], o["hold_time_s"], o["max_finger_force_N"]) !=
                   (r["line_rate_per_min"], r["hold_time_s"], r["max_finger_force_N"])
                   for o in pool)
    front = {(r["line_rate_per_min"], r["hold_time_s"], r["max_finger_force_N"]): r
             for r in pool if not dominated(r)}
    return sorted(front.values(), key=lambda r: (r["line_rate_per_min"], -r["hold_time_s"]))


def _output(problem: DesignProblem, space: DesignSpace, population: Population,
            baseline: Scored, cap: float, results: dict, t0: float) -> RunOutput:
    caps = np.full(len(population.members), cap)
    base_rate = rate_of(baseline)
    base_kept = keeps_rules(baseline, caps, problem.min_hold)
    kept = [k for k, r in results.items() if r["status"] == VERIFIED]
    best_key = max(kept, key=lambda k: (results[k]["line_rate_per_min"],
                                        results[k]["hold_time_s"])) if kept else None
    rows = [{"case": k, "finger_sets": r["sets"], "status": r["status"],
             "line_rate_per_min": r["line_rate_per_min"], "worst_hold_time_s": r["hold_time_s"],
             "max_finger_force_N": r["max_finger_force_N"], **r["line"],
             "limit": r["limit"], "message": r["message"], "wall_time_s": r["wall_time_s"]}
            for k, r in results.items()]
    trials = [dict(t, finger_sets=r["sets"]) for r in results.values() for t in r["trials"]]
    front = pareto(trials)
    if best_key is None:
        status, message = Status.FAILED_VERIFICATION, (
            f"no number of finger sets ({', '.join(str(r['sets']) for r in results.values())})"
            f" gives a verified design that holds every bird {problem.min_hold:g} s under the "
            f"{cap:.2f} N cap without a jam")
    else:
        best = results[best_key]
        own = best["sets"] == space.baseline.grasper.sets and \
            np.array_equal(best["d"], space.scale(space.base_values))
        status = Status.NO_IMPROVEMENT if own and base_kept else Status.VERIFIED
        message = (f"{best['line_rate_per_min']:.1f} birds/min with {best['sets']} finger sets "
                   f"at {best['line']['drum_speed_rpm']:.1f} rpm, every bird held at least "
                   f"{problem.min_hold:g} s (worst {best['hold_time_s']:.4f} s) under the "
                   f"{cap:.2f} N cap, verified at 4x finer resolution; the baseline: "
                   f"{base_rate:.1f} birds/min" + ("" if base_kept else
                                                   ", which does not keep the rules"))
    best = results[best_key] if best_key else max(
        results.values(), key=lambda r: (r["line_rate_per_min"], r["hold_time_s"]))
    verification = dict(best["verification"], cap_N=cap)
    result = {
        "kind": "design", "name": problem.name, "toolkit_version": __version__,
        "units": {"length": "m", "force": "N", "time": "s", "speed": "m/s",
                  "drum_speed": "rad/s", "line_rate": "birds/min"},
        "description": problem.description, "status": str(status), "message": message,
        "objective": {"goal": "throughput", "min_hold_s": problem.min_hold,
                      "hold_time_s": best["hold_time_s"],
                      "source": "the pattern search's simulation",
                      "finger_model": space.baseline.finger_model},
        "line_rate_per_min": best["line_rate_per_min"],
        "design": best["design"], "verification": verification,
        "cap": {"N": cap, "given_as": problem.caps[0].describe()},
        "line": {"cases": rows, "best_case": best_key,
                 "baseline": {"line_rate_per_min": base_rate, "keeps_rules": base_kept,
                              **line_of(space, space.scale(space.base_values)),
                              "birds": bird_rows(population, baseline)},
                 "optimum_birds": best["birds"], "thesis_rate_per_min": THESIS_RATE,
                 "kill_line_rate_per_min": KILL_LINE_RATE,
                 "limit": best["limit"]},
        "baseline": {"hold_time_s": baseline.hold, "max_finger_force_N": baseline.peak,
                     "line_rate_per_min": base_rate,
                     "design": {v.name: v.baseline for v in space.variables}},
        "pareto": front,
        "numerics": numerics(),
        "wall_time_s": time.perf_counter() - t0,
    }
    tables = {"line.csv": rows, "pareto.csv": front,
              "birds.csv": [dict(b, design=label) for label, birds in
                            (("baseline", result["line"]["baseline"]["birds"]),
                             ("optimum", best["birds"])) for b in birds]}
    # the limiting bird's 4x finer run of the answer, for the report's figures
    _, birds = sets_population(problem, best["sets"])
    limiting = min(range(len(birds.members)), key=lambda b: best["birds"][b]["hold_time_s"])
    optimum = verify(Population((birds.members[limiting],)), np.array(best["d"]),
                     problem.settings).run
    tables["timeseries.csv"] = timeseries(optimum)
    return RunOutput(result, tables, ok=status in (Status.VERIFIED, Status.NO_IMPROVEMENT),
                     artifacts={"baseline": baseline.run, "optimum": optimum})


def faster_limit(outcome, min_hold: float, space: DesignSpace) -> str:
    """What keeps the search's answer from a higher rate: the rules broken
    by the slowest faster design it simulated (the longest-held of those),
    or the drum speed's bound, or the budget."""
    answer = rate_of(outcome.best)
    faster = [t.value for t in outcome.trials if rate_of(t.value) > answer * (1 + 1e-9)]
    if not faster:
        names = [v.name for v in space.variables]
        if "drum_speed" in names and outcome.best.d[names.index("drum_speed")] >= 1.0:
            return "the drum speed's upper bound"
        return "no faster design was simulated within the search's budget"
    nearest = min(faster, key=lambda v: (rate_of(v), -v.hold))
    rules = broken(nearest, outcome.caps, min_hold) or ["none (a later step would keep them)"]
    return (f"the nearest faster design simulated, {rate_of(nearest):.1f} birds/min, breaks: "
            + "; ".join(rules))
