"""Grasp level: the integrators and their steps on a grasp scene's window.

Each setting simulates the same window of the scene: from the earliest time
a finger can reach the bird (nothing touches before it, so the fingers and
the bird are advanced there and the bird starts riding the belt) to
:data:`SETTLE` s after the last finger can, or the scene's end. Errors: the
longest hold (s) and the peak finger force (N), relative to a reference at 4x
the default resolution (max step / 4, tolerances / 4^4). Wall time: one run
(setup and integration).
"""

from __future__ import annotations

import math
from dataclasses import asdict, replace

from design.io.grasp_scene import GraspScene
from design.reproduce.grasp import advanced
from design.run import Progress
from design.run.grasp import setup_of
from design.solvers.grasp.integrate import IntegratorSettings
from design.solvers.grasp.simulation import GraspSetup, setup_reach_windows, simulate_grasp
from design.tradeoff.study import Row, Study, relative

DEFAULT = IntegratorSettings()
#: the integrator settings studied: short name -> settings
CASES = {
    "adaptive rk45 (default)": DEFAULT,
    "adaptive rk45, max step 5 ms": IntegratorSettings(max_step=5e-3),
    "adaptive rk45, max step 20 ms": IntegratorSettings(max_step=2e-2),
    "adaptive rk45, rtol 1e-6": IntegratorSettings(rtol=1e-6, atol=1e-8),
    "adaptive dop853": IntegratorSettings(stepper="dop853"),
    # implicit, for scenes whose fingers' regularised friction is stiff
    "adaptive radau": IntegratorSettings(stepper="radau"),
    "adaptive bdf": IntegratorSettings(stepper="bdf"),
    # the thesis's method as it ran: no bound on a step's estimated local error
    "bdf4 (thesis) 16.6 ms": IntegratorSettings(integrator="bdf4", step=16.6e-3,
                                                max_local_error=math.inf),
    "bdf4 (thesis) 5.6 ms": IntegratorSettings(integrator="bdf4", step=5.6e-3,
                                               max_local_error=math.inf),
    "bdf4 1.4 ms": IntegratorSettings(integrator="bdf4", step=1.4e-3),
}
QUICK_CASES = ("adaptive rk45 (default)", "adaptive rk45, max step 5 ms",
               "bdf4 (thesis) 5.6 ms")
#: the reference's resolution, times the default's
REFERENCE_FACTOR = 4.0
#: simulated time (s) after the last finger can reach the bird: it lands
SETTLE = 0.25


def setting(s: IntegratorSettings) -> dict:
    """The settings that matter for the integrator chosen."""
    keys = ("integrator", "step") if s.integrator == "bdf4" else \
        ("integrator", "stepper", "rtol", "atol", "max_step")
    return {k: v for k, v in asdict(s).items() if k in keys}


def method(s: IntegratorSettings) -> str:
    """The integrator's name, with its stepper if adaptive."""
    return s.integrator if s.integrator == "bdf4" else f"{s.integrator} {s.stepper}"


def window(setup: GraspSetup) -> tuple[float, float]:
    """Start and end (s) of the part of the scene in which fingers act; the
    start is no later than a belt deceleration begins."""
    spans = [w for finger in setup_reach_windows(setup) for w in finger]
    if not spans:
        return 0.0, setup.duration
    start = min(lo for lo, _ in spans)
    end = min(setup.duration, max(hi for _, hi in spans) + SETTLE)
    conv = setup.conveyor
    if conv.decelerates and conv.start_time is not None:
        start = min(start, conv.start_time)
    elif conv.decelerates and conv.speed > 0:
        start = min(start, max(0.0, (conv.start_position - setup.start_x) / conv.speed))
    return start, end


def shifted(setup: GraspSetup, start: float, end: float) -> GraspSetup:
    """The scene from ``start`` to ``end`` (s): fingers and bird where they are
    at ``start``, valid while nothing has touched the bird before it."""
    conv = setup.conveyor
    if conv.start_time is not None:
        conv = replace(conv, start_time=conv.start_time - start)
    return replace(setup, grasper=advanced(setup.grasper, start, setup.drum_speed),
                   start_x=setup.start_x + setup.conveyor.speed * start, conveyor=conv,
                   duration=end - start)


def simulate(setup: GraspSetup, settings: IntegratorSettings, contact_nodes: int = 6,
             reach_filter: bool = True) -> dict:
    """One run's hold (s), peak finger force (N), wall time (s) and statistics."""
    run = simulate_grasp(setup, settings, contact_nodes, reach_filter)
    s = run.summary
    return {"wall_s": run.trajectory.wall_time + run.setup_time,
            "hold_time_s": s["hold_time_s"], "max_finger_force_N": s["max_finger_force_N"],
            "max_finger_force_finger": s["max_finger_force_finger"],
            "steps": run.trajectory.steps, "contact_solves": run.contact_solves,
            "skipped_finger_evaluations": run.skipped, "ok": run.trajectory.ok,
            "message": run.trajectory.message}


def study(scene: GraspScene, quick: bool = False, progress: Progress | None = None) -> Study:
    """The :data:`CASES` (:data:`QUICK_CASES` with ``quick``) against the reference."""
    full = setup_of(scene)
    start, end = window(full)
    setup = shifted(full, start, end)
    opts = (scene.settings.contact_nodes, scene.settings.reach_filter)
    ref_settings = DEFAULT.finer(REFERENCE_FACTOR)
    plan = {"reference (4x finer)": ref_settings,
            **{k: v for k, v in CASES.items() if not quick or k in QUICK_CASES}}
    rows: list[Row] = []
    ref = None
    for name, settings in plan.items():
        if progress:
            progress(f"grasp: {name}, t = {start:.3f}..{end:.3f} s")
        got = simulate(setup, settings, *opts)
        ref = got if ref is None else ref
        rows.append(Row(
            "grasp", method(settings), name, setting(settings),
            {"hold_time": relative(got["hold_time_s"], ref["hold_time_s"]),
             "peak_force": relative(got["max_finger_force_N"], ref["max_finger_force_N"])},
            got["wall_s"], got["wall_s"], is_default=settings == DEFAULT,
            is_reference=not rows, converged=got["ok"], note=got["message"],
            values={k: got[k] for k in ("hold_time_s", "max_finger_force_N", "steps",
                                        "contact_solves")}))
    scene_setting = setting(scene.settings.integrator)
    return Study(
        "grasp", rows,
        reference={"setting": setting(ref_settings),
                   "what": f"the default adaptive integrator at {REFERENCE_FACTOR:g}x finer "
                           f"resolution", "wall_time_s": ref["wall_s"],
                   **{k: v for k, v in ref.items() if k != "wall_s"}},
        metrics={"hold_time": "longest hold (s, bird off the belt) against the reference's",
                 "peak_force": "peak finger force (N) against the reference's"},
        scene_setting=scene_setting if any(r.setting == scene_setting for r in rows) else None,
        notes=[f"simulated t = {start:.3f}..{end:.3f} s of the scene's {full.duration:g} s: "
               f"from the first time a finger can reach the bird to {SETTLE:g} s after the "
               f"last; contact nodes {opts[0]}; wall time: one run each (setup and "
               f"integration)"])
