"""Running a grasp scene: integrate, summarise, and tabulate the time series."""

from __future__ import annotations

from dataclasses import fields

import numpy as np

from design import __version__
from design.io.grasp_scene import GraspScene
from design.io.scene_writer import grasp_spec
from design.run import Progress, RunOutput
from design.run.animation import animation_record
from design.solvers.grasp.simulation import GraspRun, GraspSetup, simulate_grasp
from design.solvers.grasp.validity import validity_problems


def setup_of(scene: GraspScene) -> GraspSetup:
    """The scene's physical system alone (its name and settings dropped)."""
    return GraspSetup(**{f.name: getattr(scene, f.name) for f in fields(GraspSetup)})


def timeseries(run: GraspRun) -> list[dict]:
    """One row per recorded instant: bird state, belt forces, each finger's
    force on the bird (right drum, world frame, N), its contact point on the
    bird (bird frame, m) and its normal force on the belt (N). The left
    drum's fingers are the mirror images."""
    names = [gf.name for gf in run.setup.grasper.fingers]
    rows = []
    for r in run.trajectory.records:
        row = {"t_s": r.t, "X_m": r.y[0], "Z_m": r.y[1], "theta_rad": r.y[2],
               "Xdot_m_s": r.y[3], "Zdot_m_s": r.y[4], "thetadot_rad_s": r.y[5],
               "N_N": r.normal, "belt_friction_N": r.friction, "belt_speed_m_s": r.belt_speed,
               "mode": r.mode}
        for n, f in zip(names, r.fingers):
            p = f.body_point
            row.update({f"F{n}_x_N": f.force[0], f"F{n}_y_N": f.force[1],
                        f"F{n}_z_N": f.force[2], f"F{n}_N": f.magnitude,
                        f"B{n}_N": f.belt_force,
                        f"P{n}_x_m": None if p is None else p[0],
                        f"P{n}_y_m": None if p is None else p[1],
                        f"P{n}_z_m": None if p is None else p[2]})
        rows.append(row)
    return rows


def run(scene: GraspScene, progress: Progress | None = None) -> RunOutput:
    s = scene.settings
    result_run = simulate_grasp(setup_of(scene), s.integrator, s.contact_nodes, s.reach_filter,
                                progress)
    return RunOutput(result_dict(scene, result_run), {"timeseries.csv": timeseries(result_run)},
                     ok=result_run.trajectory.ok, artifacts={"run": result_run})


def result_dict(scene: GraspScene, r: GraspRun) -> dict:
    traj = r.trajectory
    rows = timeseries(r)
    columns = {k: [row[k] for row in rows] for k in rows[0]} if rows else {}
    i = scene.settings.integrator
    return {
        "kind": "grasp", "name": scene.name, "toolkit_version": __version__,
        "units": {"length": "m", "force": "N", "angle": "rad", "time": "s", "mass": "kg"},
        "grasper": scene.grasper.describe(), "bird": scene.bird.describe(),
        "conveyor": scene.conveyor.describe(), "drum_speed": scene.drum_speed,
        "start_X": scene.start_x,
        "friction": {"finger": scene.finger_friction, "conveyor": scene.conveyor_friction,
                     "finger_belt": scene.finger_belt_friction},
        "belt": scene.belt.describe(),
        "legs": {"stiffness": scene.legs.stiffness, "damping": scene.legs.damping},
        "duration": scene.duration,
        "solver": {"integrator": i.integrator, "rtol": i.rtol, "atol": i.atol,
                   "max_step": i.max_step, "stepper": i.stepper, "step": i.step,
                   "max_local_error": i.max_local_error,
                   "contact_nodes": scene.settings.contact_nodes,
                   "reach_filter": scene.settings.reach_filter},
        "summary": r.summary,
        "animation": animation_record({scene.name or "grasp": (
            grasp_spec(r.setup, scene.settings, scene.name, scene.description), rows)}, None),
        "stats": {"wall_time_s": traj.wall_time, "setup_time_s": r.setup_time,
                  "steps": traj.steps, "contact_solves": r.contact_solves,
                  "finger_evaluations_skipped": r.skipped,
                  "reach_windows_s": r.windows},
        "timeseries": columns,
    }


def summary_line(result: dict) -> str:
    """The command's closing line for a grasp run that finished: the hold, a
    jam, the peak, how high the bird went, and the model's validity problems
    (units s, N, mm, deg)."""
    s = result["summary"]
    problems = validity_problems(s["validity"])
    caveat = " (by a model outside its validity)" if problems else ""
    peak = (f"peak finger force {s['max_finger_force_N']:.2f} N at "
            f"{s['max_finger_force_finger']} (t = {s['max_finger_force_time_s']:.3f} s)"
            if s["max_finger_force_N"] > 0 else "no finger touched the bird")
    jammed = f"; JAMMED: {'; '.join(s['jam'])}" if s["jam"] else ""
    line = (f"finished{caveat}: hold {s['hold_time_s']:.4f} s (longest N = 0 window the bird "
            f"is put back from; {s['total_hold_s']:.4f} s in all){jammed}, {peak}, centre rise "
            f"{1e3 * s['centre_rise_m']:.1f} mm, belt clearance "
            f"{1e3 * s['belt_clearance_m']:.1f} mm, pitch up to "
            f"{np.degrees(s['max_pitch_rad']):.1f} deg")
    return line + (f"; {'; '.join(problems)}" if problems else "")
