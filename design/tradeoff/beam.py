"""Beam level: every beam method at several resolutions on a beam scene's loads.

Error: the load points' distance from the reference's (m), relative to the
reference load point's distance from the base. Reference: Frisch-Fay (closed
form) for a uniform finger, collocation on 128 intervals otherwise. Wall
time: best of several solves of all the scene's loads, after one warm-up
solve that builds and caches the method's CasADi functions.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

from design.io.beam_scene import BeamScene
from design.physics.beam import BeamSolution, Finger, PointLoad
from design.run import Progress
from design.solvers.beam import DEFAULT_METHOD, METHODS, solve_beam
from design.tradeoff.study import Row, Study, relative, timed

#: resolutions (``nodes``) per method; None: the method's default
RESOLUTIONS = {
    "small-deflection": [None],
    "frisch-fay": [None],
    "shooting": [64, 256, 1024],
    "fdm": [99, 399, 1599],
    "collocation": [4, 8, 16, 32, 64],
}
QUICK_RESOLUTIONS = {**RESOLUTIONS, "shooting": [64, 256], "collocation": [4, 8, 16, 32]}
#: collocation intervals of the reference for a non-uniform finger
REFERENCE_INTERVALS = 128


def reference_setting(finger: Finger) -> tuple[str, int]:
    """(method, nodes) of the high-accuracy reference for ``finger``."""
    if finger.stiffness.uniform:
        return "frisch-fay", METHODS["frisch-fay"].default_nodes
    return "collocation", REFERENCE_INTERVALS


def reference(finger: Finger, loads: Sequence[PointLoad]) -> np.ndarray:
    """Load points (n, 2), m, of the high-accuracy reference."""
    method, nodes = reference_setting(finger)
    return tips(solve_beam(finger, loads, method, nodes=nodes))


def tips(sols: Sequence[BeamSolution]) -> np.ndarray:
    """Load points (n, 2) of solutions, m."""
    return np.array([[s.x[-1], s.y[-1]] for s in sols])


def setting(method: str, nodes: int | None) -> dict:
    """A beam setting as a table entry: the method and its resolution."""
    return {"method": method, "nodes": int(nodes or METHODS[method].default_nodes)}


def study(scene: BeamScene, quick: bool = False, progress: Progress | None = None) -> Study:
    """Every applicable method at every resolution of :data:`RESOLUTIONS`
    (:data:`QUICK_RESOLUTIONS`, fewer repeats, with ``quick``)."""
    finger, loads = scene.finger, list(scene.loads)
    repeat, budget = (3, 0.3) if quick else (5, 1.0)
    ref_method, ref_nodes = reference_setting(finger)
    studied = [(m, n) for m, ns in (QUICK_RESOLUTIONS if quick else RESOLUTIONS).items()
               for n in ns]
    plan = [(ref_method, ref_nodes)] + [p for p in studied
                                        if setting(*p) != setting(ref_method, ref_nodes)]
    notes = []
    rows: list[Row] = []
    ref = None
    for method, nodes in plan:
        reasons = METHODS[method](finger).check()
        if reasons:
            notes.append(f"{method} not run: {'; '.join(reasons)}")
            continue
        if progress:
            progress(f"beam: {method}, nodes {setting(method, nodes)['nodes']}")
        sols, best, first = timed(lambda: solve_beam(finger, loads, method, nodes=nodes),
                                  repeat, warmup=True, budget=budget)
        got = tips(sols)
        ref = got if ref is None else ref
        rows.append(Row(
            "beam", method, f"{method} {setting(method, nodes)['nodes']}",
            setting(method, nodes), {"load_point": relative(got, ref)}, best, first,
            is_default=setting(method, nodes) == setting(DEFAULT_METHOD, None),
            is_reference=not rows, converged=all(s.converged for s in sols),
            values={"load_point_error_m": float(np.max(np.linalg.norm(got - ref, axis=1)))}))
    scene_setting = setting(scene.solver.method, scene.solver.nodes)
    return Study(
        "beam", rows,
        reference={"setting": setting(ref_method, ref_nodes),
                   "what": "Frisch-Fay closed form (uniform finger)" if ref_method ==
                   "frisch-fay" else f"collocation on {ref_nodes} intervals, degree 4",
                   "load_points_m": ref, "wall_time_s": rows[0].wall_time_s},
        metrics={"load_point": "largest load-point distance from the reference (m) over "
                               "the largest reference load-point distance from the base (m)"},
        scene_setting=scene_setting if any(r.setting == scene_setting for r in rows) else None,
        notes=notes + [f"{len(loads)} load(s); wall time: the best of at least {repeat} "
                       f"solves of all of them (more, up to {budget:g} s, for cheap ones), "
                       f"after a warm-up solve (first run: that warm-up)"])
