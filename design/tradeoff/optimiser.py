"""Design level: the optimiser's time grid, on the problem's baseline design.

For each grid step, the fixed-design NLP on the baseline's own simulated
schedule (:func:`~design.solvers.optimize.trust_region.optimiser_view`, the
number the optimiser would claim for the design) against the independent
simulation at 4x finer resolution (:func:`~design.solvers.optimize.trust_region.verify`).
Error: the hold time (s), relative. Wall time: building and solving that NLP
(the baseline's simulation, which every grid starts from, is common to all
and reported apart). Steps studied: twice the toolkit's default, the
default, the problem's own and, unless quick, half the default.
"""

from __future__ import annotations

import math
import time
from dataclasses import replace

from design.io.design_problem import DesignProblem
from design.run import Progress
from design.run.solve import design_space
from design.solvers.optimize.transcription import NLPSettings
from design.solvers.optimize.trust_region import (VIEW_FEASIBLE, feasible, optimiser_view,
                                                simulate, verify)
from design.tradeoff.study import Row, Study, relative

DEFAULT = NLPSettings()


def steps(own: float, quick: bool) -> list[float]:
    """Grid steps (s) to study, coarsest first: twice the default, the
    default, the problem's own and, unless quick, half the default."""
    out = {2 * DEFAULT.time_step, DEFAULT.time_step, own}
    if not quick:
        out.add(DEFAULT.time_step / 2)
    return sorted(out, reverse=True)


def setting(nlp: NLPSettings) -> dict:
    return {"time_step": nlp.time_step, "beam_intervals": nlp.beam_intervals}


def study(problem: DesignProblem, quick: bool = False, progress: Progress | None = None
          ) -> Study:
    """The fixed-design NLP's hold at each grid step against the fine simulation."""
    say = progress or (lambda message: None)
    loop = problem.settings
    space = design_space(problem, progress)
    d0 = space.scale(space.base_values)
    say("design: the baseline at 4x the optimiser's resolution (the reference)")
    t0 = time.perf_counter()
    fine = verify(space, d0, loop)
    ref_wall = time.perf_counter() - t0
    say("design: the baseline's simulation (the schedule every grid is built on)")
    t0 = time.perf_counter()
    base = simulate(space, d0, loop)
    sim_wall = time.perf_counter() - t0
    plan = [replace(loop.nlp, time_step=dt) for dt in steps(loop.nlp.time_step, quick)]
    if setting(DEFAULT) not in [setting(n) for n in plan]:
        plan.append(replace(loop.nlp, time_step=DEFAULT.time_step,
                            beam_intervals=DEFAULT.beam_intervals))
    rows = []
    for nlp in plan:
        say(f"design: fixed-design NLP on a {1e3 * nlp.time_step:g} ms grid, "
            f"{nlp.beam_intervals} beam intervals")
        t0 = time.perf_counter()
        try:
            view, error = optimiser_view(space, base, replace(loop, nlp=nlp), problem.rules), ""
        except (RuntimeError, ValueError) as exc:
            view, error = None, str(exc)
        wall = time.perf_counter() - t0
        hold = view.hold_time if view is not None else math.nan
        violation = view.violation if view is not None and view.history \
            else math.nan
        note = "" if feasible(view) else \
            f"the NLP could not be built or solved: {error}" if view is None else \
            f"not feasible: constraint violation {violation:.3g} > {VIEW_FEASIBLE:g}"
        rows.append(Row(
            "design", "fixed-design NLP", f"{1e3 * nlp.time_step:g} ms grid, "
            f"{nlp.beam_intervals} beam intervals", setting(nlp),
            {"hold_time": relative(hold, fine.hold)}, wall, wall,
            is_default=setting(nlp) == setting(DEFAULT), converged=feasible(view), note=note,
            values={"nlp_hold_time_s": hold, "constraint_violation": violation,
                    "ipopt_status": None if view is None else view.status,
                    "ipopt_iterations": None if view is None else view.iterations,
                    "nlp_variables": None if view is None else view.size["variables"]}))
    return Study(
        "design", rows,
        reference={"setting": {"simulator": "adaptive, 4x finer than the problem's grid"},
                   "what": "the baseline design's simulation at 4x the optimiser's resolution "
                           "(trust_region.verify)",
                   "hold_time_s": fine.hold, "max_finger_force_N": fine.peak,
                   "wall_time_s": ref_wall, "schedule_simulation_wall_s": sim_wall,
                   "schedule_simulation_hold_time_s": base.hold},
        metrics={"hold_time": "the NLP's hold (s) against the fine simulation's"},
        scene_setting=setting(loop.nlp),
        notes=[f"baseline design; wall time: building and solving the fixed-design NLP, "
               f"one run each; the baseline simulation it starts from took {sim_wall:.1f} s "
               f"and is common to all"])
