"""Running a design problem: optimise, verify, tabulate (``design solve``)."""

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
from design.solve.optimize.transcription import rule_margins
from design.solve.optimize.trust_region import Outcome, certify, optimise, verdict, verify
from design.solve.optimize.variables import (DesignSpace, Variable, parameters_of,
                                             timed_conveyor)

#: a scaled variable this close to 0 or 1 sits on its bound
ACTIVE = 1e-3


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


def run(problem: DesignProblem, progress: Progress | None = None) -> RunOutput:
    t0 = time.perf_counter()
    say = progress or (lambda message: None)
    space = design_space(problem, progress)
    settings = problem.settings
    d0 = space.scale(space.base_values)
    say("simulating the baseline at 4x the optimiser's resolution")
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
        fine = verify(space, outcome.best.d, settings)
        entries[k] = _entry(space, problem, outcome, claim, fine, cap, cap_spec)
        outcomes[k] = (outcome, fine)
        start = outcome.best.d
    entries = [entries[k] for k in range(len(caps))]
    primary, (outcome, fine) = entries[0], outcomes[0]
    result = {
        "kind": "design", "name": problem.name, "toolkit_version": __version__,
        "units": {"length": "m", "force": "N", "angle": "rad", "time": "s",
                  "speed": "m/s", "acceleration": "m/s^2", "drum_speed": "rad/s"},
        "description": problem.description,
        "problem": {"variables": {v.name: {"lower": v.lo, "upper": v.hi, "baseline": v.baseline,
                                           "unit": v.unit} for v in space.variables},
                    "caps": [c.describe() for c in problem.caps],
                    "rules": vars(problem.rules)},
        **primary,
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
    spec = grasp_spec(space.setup(outcome.best.d), problem.scene.settings,
                      f"{problem.name}_optimum",
                      f"Optimised by design solve from {problem.name} (cap "
                      f"{primary['verification']['cap_N']:.3g} N).")
    return RunOutput(result, tables, ok=all(e["verification"]["passed"] for e in entries),
                     files={"optimum.yaml": scene_yaml(spec)},
                     artifacts={"baseline": baseline.run, "optimum": fine.run})


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
    if check["passed"] and check["model_warnings"]:
        status = "verified by a model outside its validity"
        message = ("the independent simulation confirms the design, but the grasp model is "
                   "outside its validity: " + "; ".join(check["model_warnings"]))
    elif check["passed"]:
        status, message = "verified", "the independent simulation confirms the design"
    elif not np.isfinite(claimed):
        status = "optimiser failed"
        errors = list(dict.fromkeys(i.get("error") or i.get("ipopt_status", "")
                                    for i in outcome.iterations))
        message = "no optimisation step could be computed: " + "; ".join(errors)
    elif not outcome.feasible:
        status = "infeasible"
        message = _diagnosis(space, problem, best, cap, variables)
    else:
        status = "failed verification"
        message = (f"the independent simulation disagrees: hold {fine.hold:.4f} s against the "
                   f"optimiser's {claimed:.4f} s, peak {fine.peak:.2f} N against the "
                   f"cap {cap:.2f} N")
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
