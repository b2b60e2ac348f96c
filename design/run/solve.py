"""Running a design problem: optimise, verify, tabulate (``design solve``).

A run ends in one of four statuses (result.json's ``status``; the command's
exit status in brackets): ``verified`` (0), the independent simulation
confirms the optimiser's design; ``no improvement found`` (0), the loop
accepted no design and the baseline, which keeps the cap, is the answer;
``failed verification`` (1), the simulation disagrees with the optimiser or
the design breaks the cap; ``error`` (1), the optimiser could not work
(every NLP failed, or it could not evaluate its own design). Bad input (2)
and Ctrl-C (130) write no result.

result.json's ``profile`` says where the run's time went (wall time per
phase, Ipopt's function evaluations, peak memory: design/solve/optimize/profile.py).
"""

from __future__ import annotations

import time
from dataclasses import replace

import numpy as np

from design import __version__
from design.io.design_problem import DesignProblem
from design.io.scene_writer import grasp_spec, scene_yaml
from design.run import Progress, RunOutput
from design.run.grasp import setup_of, timeseries
from design.solve.grasp.simulation import simulate_grasp
from design.solve.optimize.profile import RESULT, SETUP, VERIFICATION, Profile
from design.solve.optimize.transcription import rule_margins
from design.solve.optimize.trust_region import Outcome, certify, optimise, verdict, verify
from design.solve.optimize.variables import (DesignSpace, Variable, parameters_of,
                                             timed_conveyor)
from design.study.cases import StudyOptions

#: a scaled variable this close to 0 or 1 sits on its bound
ACTIVE = 1e-3
#: how a run ends; the first two are a success (exit status 0)
VERIFIED, NO_IMPROVEMENT = "verified", "no improvement found"
FAILED, ERROR = "failed verification", "error"


def design_space(problem: DesignProblem, progress: Progress | None = None) -> DesignSpace:
    """The problem's variables around its baseline grasp, the belt's
    deceleration timed (a position trigger becomes the time the baseline's
    bird reaches it)."""
    setup = setup_of(problem.scene)
    conveyor = setup.conveyor
    start = conveyor.start_time
    if conveyor.decelerates and start is None:
        if progress:
            progress("timing the belt's deceleration from a baseline simulation")
        run = simulate_grasp(setup, problem.settings.simulator, problem.settings.contact_nodes)
        slows = [t for t, name in run.trajectory.events if name == "belt slows"]
        start = slows[0] if slows else setup.duration
    setup = replace(setup, conveyor=timed_conveyor(conveyor, start))
    base = parameters_of(setup)
    return DesignSpace(setup, [Variable(n, lo, hi, base[n])
                               for n, (lo, hi) in problem.variables.items()])


def run(problem: DesignProblem, progress: Progress | None = None,
        study: StudyOptions | None = None) -> RunOutput:
    t0 = time.perf_counter()
    profile = Profile()
    say = progress or (lambda message: None)
    with profile.phase(SETUP):
        space = design_space(problem, progress)
    settings = problem.settings
    d0 = space.scale(space.base_values)
    say("simulating the baseline at 4x the optimiser's resolution")
    with profile.phase(VERIFICATION):
        baseline = verify(space, d0, settings)
    caps = [c.resolve(baseline.peak) for c in problem.caps]
    entries, outcomes, start = {}, {}, None
    # tightest cap first: each design is then feasible for the next, looser
    # cap and warm-starts it, so the hold time cannot fall as the cap rises
    for k in sorted(range(len(caps)), key=caps.__getitem__):
        cap_spec, cap = problem.caps[k], caps[k]
        say(f"cap {k + 1} of {len(problem.caps)}: {cap:.2f} N ({cap_spec.describe()})")
        outcome = optimise(space, cap, settings, problem.rules, start, progress)
        claim = certify(space, outcome, settings, problem.rules, progress)
        say("verifying at 4x finer resolution")
        with profile.phase(VERIFICATION):
            fine = verify(space, outcome.best.d, settings)
        with profile.phase(RESULT):
            entries[k] = _entry(space, problem, outcome, claim, fine, cap, cap_spec)
        profile.merge(outcome.profile)
        outcomes[k] = (outcome, fine)
        start = outcome.best.d
    with profile.phase(RESULT):
        output = _output(problem, space, [entries[k] for k in range(len(caps))], outcomes[0],
                         baseline, t0)
    output.result["profile"] = profile.summary()
    return output


def _output(problem: DesignProblem, space: DesignSpace, entries: list[dict], primary_outcome,
            baseline, t0: float) -> RunOutput:
    """The run's result, tables and files; the first cap's entry is the
    primary one (its design and verification are reported)."""
    primary, (outcome, fine) = entries[0], primary_outcome
    status, message = overall_status(entries)
    result = {
        "kind": "design", "name": problem.name, "toolkit_version": __version__,
        "units": {"length": "m", "force": "N", "angle": "rad", "time": "s",
                  "speed": "m/s", "acceleration": "m/s^2", "drum_speed": "rad/s"},
        "description": problem.description,
        "problem": {"variables": {v.name: {"lower": v.lo, "upper": v.hi, "baseline": v.baseline,
                                           "unit": v.unit} for v in space.variables},
                    "caps": [c.describe() for c in problem.caps],
                    "rules": vars(problem.rules)},
        **primary, "status": status, "message": message,
        "baseline": {"hold_time_s": baseline.hold,
                     "hold_windows": baseline.run.summary["hold_windows"],
                     "max_finger_force_N": baseline.peak,
                     "max_finger_force_finger": baseline.run.summary["max_finger_force_finger"],
                     "design": {v.name: v.baseline for v in space.variables}},
        "wall_time_s": time.perf_counter() - t0,
    }
    if problem.pareto:
        result["pareto"] = sorted((_pareto_row(e) for e in entries), key=lambda r: r["cap_N"])
    tables = {"design.csv": primary["variables"], "timeseries.csv": timeseries(fine.run)}
    if problem.pareto:
        tables["pareto.csv"] = result["pareto"]
    files = {}
    if primary["status"] in (VERIFIED, FAILED):        # else the baseline: no optimum
        spec = grasp_spec(space.setup(outcome.best.d), problem.scene.settings,
                          f"{problem.name}_optimum",
                          f"Optimised by design solve from {problem.name} (cap "
                          f"{primary['verification']['cap_N']:.3g} N).")
        files["optimum.yaml"] = scene_yaml(spec)
    return RunOutput(result, tables, ok=status in (VERIFIED, NO_IMPROVEMENT), files=files,
                     artifacts={"baseline": baseline.run, "optimum": fine.run})


def overall_status(entries: list[dict]) -> tuple[str, str]:
    """The run's status and message: the first cap's (whose design the
    result reports), unless another cap ended in an error or failed."""
    worst = next((s for s in (ERROR, FAILED) if s in [e["status"] for e in entries]),
                 entries[0]["status"])
    entry = next(e for e in entries if e["status"] == worst)
    if entry is entries[0]:
        return worst, entry["message"]
    return worst, f"cap {entry['cap']['N']:.2f} N: {entry['message']}"


def status_line(result: dict) -> str:
    """The command's closing line for a design result: its status and numbers."""
    v, b, status = result["verification"], result["baseline"], result["status"]
    peak = f"peak finger force {v['max_finger_force_N']:.2f} N (cap {v['cap_N']:.2f} N)"
    if status == ERROR:
        return f"error: {result['message']}"
    if status == NO_IMPROVEMENT:
        return (f"no improvement found: the design is the baseline, unchanged; hold "
                f"{v['hold_time_s']:.4f} s, {peak}")
    caveat = " (by a model outside its validity)" if status == VERIFIED and \
        v["model_warnings"] else ""
    return (f"{status}{caveat}: hold {v['hold_time_s']:.4f} s in the independent simulation "
            f"(optimiser {result['objective']['hold_time_s']:.4f} s; baseline "
            f"{b['hold_time_s']:.4f} s), {peak}")


def _entry(space: DesignSpace, problem: DesignProblem, outcome: Outcome, claim, fine, cap,
           cap_spec) -> dict:
    best, view = outcome.best, outcome.final
    claimed, source = claim
    check = verdict(claimed, fine, cap)
    d = best.d
    variables = [{"name": v.name, "unit": v.unit, "lower": v.lo, "upper": v.hi,
                  "baseline": v.baseline, "optimum": v.lo + d[i] * (v.hi - v.lo),
                  "active_bound": "lower" if d[i] < ACTIVE else "upper" if d[i] > 1 - ACTIVE
                  else ""} for i, v in enumerate(space.variables)]
    status, message = _status(space, problem, outcome, claim, check, fine, variables)
    iterations = outcome.iterations
    return {
        "status": status, "message": message,
        "design": {v["name"]: v["optimum"] for v in variables},
        "variables": variables,
        "objective": {"hold_time_s": claimed, "source": source,
                      "grid_step_s": problem.settings.nlp.time_step},
        "verification": check,
        "cap": {"N": cap, "given_as": cap_spec.describe()},
        "rules_broken": [tag for margin, tag in rule_margins(space.values(np.asarray(d, float)),
                                                             space.baseline, problem.rules)
                         if margin < -1e-9],
        "solver": {
            "ipopt_status": outcome.nlp.status if outcome.nlp else
            (iterations[-1].get("ipopt_status", "not run") if iterations else "not run"),
            "iterations": int(sum(i.get("ipopt_iterations", 0) for i in iterations)),
            "outer_iterations": len(iterations),
            "wall_time_s": outcome.wall_time,
            "nlp_size": next((i["nlp_size"] for i in reversed(iterations) if "nlp_size" in i),
                             None if view is None else view.size),
            "final_nlp": None if view is None else {
                "ipopt_status": view.status, "iterations": view.iterations,
                "wall_time_s": view.wall_time,
                "constraint_violation": view.history[-1]["violation"] if view.history else None},
            "history": iterations,
            "settings": {"time_step_s": problem.settings.nlp.time_step,
                         "beam_intervals": problem.settings.nlp.beam_intervals,
                         "max_iter": problem.settings.nlp.max_iter,
                         "outer_iterations": problem.settings.outer_iterations,
                         "trust_region": problem.settings.radius,
                         "cap_margin": problem.settings.cap_margin,
                         "ipopt": problem.settings.nlp.ipopt},
        },
    }


def _status(space, problem, outcome: Outcome, claim, check, fine, variables
            ) -> tuple[str, str]:
    """One cap's status (see the module's docstring) and why."""
    claimed, source = claim
    cap = outcome.cap
    errors = outcome.errors
    failures = f" ({len(errors)} NLP failure(s): {'; '.join(errors)})" if errors else ""
    keeps_cap = check["max_finger_force_N"] <= cap * (1 + check["cap_tolerance"])
    if outcome.every_nlp_failed:
        return ERROR, ("every NLP of the design loop failed, so no design was tried; the "
                       "baseline is unchanged and not an answer: " + "; ".join(errors))
    if outcome.best is outcome.baseline and keeps_cap:
        return NO_IMPROVEMENT, ("the design loop found no design that holds longer under "
                                "the cap; the design reported is the baseline, unchanged"
                                + failures)
    if check["passed"] and check["model_warnings"]:
        return VERIFIED, ("verified by a model outside its validity: the independent "
                          "simulation confirms the design, but the grasp model is outside "
                          "its validity: " + "; ".join(check["model_warnings"]))
    if check["passed"]:
        return VERIFIED, "the independent simulation confirms the design"
    if not np.isfinite(claimed):
        return ERROR, (f"the optimiser could not evaluate its own design ({source}), so it "
                       f"cannot be verified{failures}")
    if not outcome.feasible:
        return FAILED, "infeasible: " + _diagnosis(space, problem, outcome.best, cap, variables)
    return FAILED, (f"the independent simulation disagrees: hold {fine.hold:.4f} s against the "
                    f"optimiser's {claimed:.4f} s, peak {fine.peak:.2f} N against the "
                    f"cap {cap:.2f} N")


def _diagnosis(space, problem, best, cap, variables) -> str:
    """Why no design met the cap: the lowest peak reached and what stopped it."""
    bounds = [f"{v['name']} at its {v['active_bound']} bound" for v in variables
              if v["active_bound"]]
    values = space.values(np.asarray(best.d, float))
    rules = [tag for margin, tag in rule_margins(values, space.baseline, problem.rules)
             if margin < 1e-6]
    stops = bounds + rules
    return (f"no design within the bounds keeps every finger under {cap:.2f} N: the smallest "
            f"peak force reached is {best.peak:.2f} N (finger "
            f"{best.run.summary['max_finger_force_finger']}); "
            + ("active: " + ", ".join(stops) if stops else
               "no bound or rule is active: the trust-region loop stopped at a local optimum"))


def _pareto_row(entry: dict) -> dict:
    v = entry["verification"]
    return {"cap_N": v["cap_N"], "status": entry["status"],
            "optimiser_hold_time_s": entry["objective"]["hold_time_s"],
            "verified_hold_time_s": v["hold_time_s"],
            "verified_max_finger_force_N": v["max_finger_force_N"], "passed": v["passed"]}
