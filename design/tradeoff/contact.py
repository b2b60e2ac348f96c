"""Contact level: the contact solvers at several resolutions on a contact scene.

``robust`` (the default) at several collocation interval counts; the thesis's
Algorithm II at several FDM node counts and Algorithm I at several
tolerances, where they apply (push or pull set by hand). Errors, over all
poses: the force on the object (world frame, N) and the contact point
(finger frame, m), each relative to the reference's largest; a pose where
one finds contact and the other none counts as a zero force or point there.
Reference: ``robust`` at 4x the finest interval count studied. Wall time:
best of several builds-and-solves of the whole pass, after a warm-up one.
"""

from __future__ import annotations

import inspect

import numpy as np

from design.io.contact_scene import ContactScene
from design.run import Progress
from design.solvers.contact import CONTACT_METHODS, DEFAULT_CONTACT_METHOD, make_contact_solver
from design.tradeoff.study import Row, Study, relative, timed

#: method -> (its resolution option, values studied, values studied with --quick)
RESOLUTIONS = {
    "robust": ("intervals", [2, 4, 6, 10, 20], [3, 6, 10]),
    "thesis-2": ("nodes", [39, 77, 155, 311], [39, 155]),
    "thesis-1": ("tolerance", [5e-3, 5e-4, 5e-5], [5e-4]),
}
#: the reference's interval count, times the finest studied
REFERENCE_FACTOR = 4


def default_option(method: str) -> float:
    """The toolkit's default value of a method's resolution option."""
    arg = RESOLUTIONS[method][0]
    return inspect.signature(CONTACT_METHODS[method]).parameters[arg].default


def setting(method: str, value: float | None = None) -> dict:
    """A contact setting as a table entry: the method and its resolution."""
    arg = RESOLUTIONS[method][0]
    return {"method": method, arg: default_option(method) if value is None else value}


def label(s: dict) -> str:
    """A setting's short name, e.g. ``robust 10``."""
    return " ".join(f"{v:g}" if k != "method" else v for k, v in s.items())


def results(sols) -> tuple[np.ndarray, np.ndarray]:
    """Forces on the object (n, 2), N, world frame, and contact points (n, 2),
    m, finger frame; zero where there is no contact."""
    force = np.array([s.force_vector if s.contact else np.zeros(2) for s in sols])
    point = np.array([s.point if s.contact else (0.0, 0.0) for s in sols], float)
    return force, point


def study(scene: ContactScene, quick: bool = False, progress: Progress | None = None) -> Study:
    """Every applicable solver at the resolutions of :data:`RESOLUTIONS`."""
    poses, objects = list(scene.poses), list(scene.objects)
    repeat, budget = (1, 0.3) if quick else (3, 1.0)
    pick = 2 if quick else 1
    methods = list(RESOLUTIONS) if scene.sliding != "auto" else [DEFAULT_CONTACT_METHOD]
    ref_setting = setting("robust", REFERENCE_FACTOR * max(RESOLUTIONS["robust"][pick]))
    plan = [ref_setting] + [setting(m, v) for m in methods for v in RESOLUTIONS[m][pick]]

    def solve(s: dict):
        options = {k: v for k, v in s.items() if k != "method"}
        solver = make_contact_solver(s["method"], scene.finger, scene.friction, **options)
        return solver.solve_pass(poses, objects, scene.sliding, scene.motion)

    rows: list[Row] = []
    ref = None
    for s in plan:
        if progress:
            progress(f"contact: {label(s)}")
        sols, best, first = timed(lambda: solve(s), repeat, warmup=True, budget=budget)
        force, point = results(sols)
        ref = (force, point) if ref is None else ref
        rows.append(Row(
            "contact", s["method"], label(s), s,
            {"force": relative(force, ref[0]), "point": relative(point, ref[1])}, best, first,
            is_default=s == setting(DEFAULT_CONTACT_METHOD), is_reference=not rows,
            converged=all(x.converged for x in sols),
            note="; ".join(sorted({x.message for x in sols if not x.converged})),
            values={"force_error_N": float(np.max(np.linalg.norm(force - ref[0], axis=1))),
                    "point_error_m": float(np.max(np.linalg.norm(point - ref[1], axis=1)))}))
    extra = set(scene.options) - {RESOLUTIONS[scene.method][0]}
    scene_setting = None if extra else setting(scene.method, scene.options.get(
        RESOLUTIONS[scene.method][0]))
    notes = [f"{len(poses)} pose(s); wall time: the best of at least {repeat} builds and "
             f"solves of the pass (more, up to {budget:g} s, for cheap ones), after a warm-up "
             f"one (first run: that warm-up)"]
    if scene.sliding == "auto":
        notes.append("the thesis's algorithms not run: they need sliding set by hand "
                     "(push or pull), this scene has auto")
    return Study(
        "contact", rows,
        reference={"setting": ref_setting,
                   "what": f"robust on {ref_setting['intervals']} collocation intervals",
                   "force_on_object_N": ref[0], "point_finger_frame_m": ref[1],
                   "wall_time_s": rows[0].wall_time_s},
        metrics={"force": "largest force error on the object (N) over the largest "
                          "reference force (N)",
                 "point": "largest contact point distance from the reference's (m) over the "
                          "largest reference point's distance from the finger base (m)"},
        scene_setting=scene_setting if any(r.setting == scene_setting for r in rows) else None,
        notes=notes)
