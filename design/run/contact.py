"""Running a contact scene: every pose, as a pass when there are several."""

from __future__ import annotations

import time

import numpy as np

from design import __version__
from design.io.contact_scene import ContactScene
from design.physics.contact import ContactSolution
from design.run import Progress, RunOutput
from design.solvers.contact import make_contact_solver


def case_dict(sol: ContactSolution, obj) -> dict:
    """One pose's result, SI (m, N, rad); finger-frame and world quantities named so."""
    world = sol.shape_world
    return {
        "finger_angle": sol.pose.angle, "object_center": list(obj.center),
        "contact": sol.contact, "force": sol.force,
        "force_vector": sol.force_vector if sol.contact else np.zeros(2),
        "point": list(sol.point) if sol.contact else None,
        "point_world": sol.point_world if sol.contact else None,
        "psi": sol.psi, "alpha": sol.alpha, "arc_length": sol.arc_length,
        "tip_contact": sol.tip_contact, "sliding": sol.side, "friction": sol.friction,
        "shape": {"x": world[0], "y": world[1]},
        "shape_finger_frame": {"s": sol.shape_s, "x": sol.shape_x, "y": sol.shape_y},
        "penetration": sol.penetration, "converged": sol.converged,
        "iterations": sol.iterations, "message": sol.message,
    }


def run(scene: ContactScene, progress: Progress | None = None) -> RunOutput:
    solver = make_contact_solver(scene.method, scene.finger, scene.friction, **scene.options)
    t0 = time.perf_counter()
    sols = solver.solve_pass(list(scene.poses), list(scene.objects), scene.sliding, scene.motion,
                             progress=progress)
    elapsed = time.perf_counter() - t0
    cases = [case_dict(s, o) for s, o in zip(sols, scene.objects)]
    result = {
        "kind": "contact", "name": scene.name, "toolkit_version": __version__,
        "units": {"length": "m", "force": "N", "angle": "rad", "time": "s"},
        "method": scene.method, "solver": {"method": scene.method, **scene.options},
        "finger": scene.finger.describe(), "drum_radius": scene.poses[0].radius,
        "object": {"semi_axes": [scene.objects[0].a, scene.objects[0].b],
                   "orientation": scene.objects[0].theta},
        "friction": scene.friction, "sliding_requested": scene.sliding,
        "motion": None if scene.motion is None else {
            "drum_speed": scene.motion.drum_speed,
            "object_velocity": list(scene.motion.object_velocity)},
        "solve_time_s": elapsed, "cases": cases,
    }
    rows = [{"finger_angle_rad": c["finger_angle"], "object_x_m": c["object_center"][0],
             "object_y_m": c["object_center"][1], "contact": c["contact"], "force_N": c["force"],
             "force_x_N": c["force_vector"][0], "force_y_N": c["force_vector"][1],
             "point_x_m": c["point"][0] if c["contact"] else None,
             "point_y_m": c["point"][1] if c["contact"] else None,
             "psi_rad": c["psi"], "alpha_rad": c["alpha"], "arc_length_m": c["arc_length"],
             "tip_contact": c["tip_contact"], "sliding": c["sliding"], "friction": c["friction"],
             "converged": c["converged"]} for c in cases]
    return RunOutput(result, {"cases.csv": rows}, ok=all(s.converged for s in sols))
