"""Writing a grasp back as a scene file that ``design simulate`` reads as it is."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import yaml

from design.io.grasp_scene import GraspSettings
from design.physics.beam import Finger
from design.physics.grasper import GraspFinger, Grasper, mounted_sets
from design.solvers.grasp.integrate import IntegratorSettings
from design.solvers.grasp.simulation import GraspSetup


def finger_spec(finger: Finger) -> dict:
    """An inline finger model (SI) for a scene file, with its out-of-plane
    rigidities when they are not the round section's defaults."""
    d = dict(finger.stiffness.describe())
    kind = d.pop("type")
    if kind == "uniform":
        out = {"length": finger.length, "EI": d["EI"]}
        out.update({key: st.describe()["EI"] for key, st in
                    (("EI_out", finger.stiff), ("GJ", finger.torsion)) if st is not None})
        return out
    E = d.pop("E")
    out = {"length": finger.length, "E": E, "I": {"type": kind, **d}}
    for key, st in (("I_out", finger.stiff), ("J", finger.torsion)):
        if st is not None:
            p = dict(st.describe())
            modulus = p.pop("E")
            out[key] = {"type": p.pop("type"), **p}
            if key == "J":       # rounded: a scaled rubber's 0.5 reads back as 0.5
                out["poisson"] = round(E / (2 * modulus) - 1, 12)
    return out


def fingers_spec(g: Grasper) -> dict:
    """The grasper's fingers as a scene file holds them: the designed set and
    ``sets`` where every other set is its copy (as the file reads back: the
    copies' design names, their drums' sets), else every finger."""
    rows = [finger_row(gf) for gf in g.fingers]
    if g.sets > 1:
        designed = [replace(gf, name=gf.design_name, family="", phase=0.0)
                    for gf in g.fingers if gf.phase == 0.0]
        if [finger_row(gf) for gf in mounted_sets(designed, g.sets)] == rows:
            return {"sets": g.sets, "fingers": [finger_row(gf) for gf in designed]}
    return {"fingers": rows}


def finger_row(gf: GraspFinger) -> dict:
    """One finger of a scene file's grasper (SI)."""
    return {"name": gf.name, "group": gf.group, "length": gf.finger.length,
            "height": gf.mount.height, "drum_radius": gf.mount.radius,
            "angle": gf.mount.angle, "phi_x": gf.mount.phi_x, "phi_y": gf.mount.phi_y,
            "finger": finger_spec(gf.finger)}


def grasp_spec(setup: GraspSetup, settings: GraspSettings, name: str, description: str) -> dict:
    """The content of a grasp scene file for ``setup`` (SI numbers only)."""
    g, b, c, i = setup.grasper, setup.bird, setup.conveyor, settings.integrator
    conveyor = {"speed": c.speed, "rate": c.rate}
    if c.decelerates:
        conveyor["final_speed"] = c.final_speed
        conveyor.update({"start_time": c.start_time} if c.start_time is not None
                        else {"start_position": c.start_position})
    return {
        "kind": "grasp", "name": name, "description": description,
        "grasper": {"spacing": g.spacing, "tilt": g.tilt, "x": g.x, **fingers_spec(g)},
        "bird": {"name": b.name, "semi_axes": [b.eta, b.lam, b.gamma], "mass": b.mass,
                 "inertia_y": b.inertia},
        "conveyor": conveyor,
        "drum_speed": setup.drum_speed,
        "start": {"X": setup.start_x},
        "friction": {"finger": setup.finger_friction, "conveyor": setup.conveyor_friction,
                     **({} if setup.belt_friction is None else {"belt": setup.belt_friction})},
        **({} if setup.belt.solid else {"belt": {
            **({} if np.isinf(setup.belt.width) else {"width": setup.belt.width}),
            **({"slots": sorted(setup.belt.slots)} if setup.belt.slots else {})}}),
        "legs": {"stiffness": setup.legs.stiffness, "damping": setup.legs.damping},
        "duration": setup.duration,
        "finger_model": setup.finger_model,
        "solver": {"integrator": i.integrator, "rtol": i.rtol, "atol": i.atol,
                   "max_step": i.max_step, "stepper": i.stepper, "step": i.step,
                   "contact_nodes": settings.contact_nodes,
                   "reach_filter": settings.reach_filter,
                   **({"max_wall_time": i.max_wall_time} if i.max_wall_time else {}),
                   **({"max_local_error": i.max_local_error}
                      if i.max_local_error != IntegratorSettings.max_local_error else {})},
    }


def scene_yaml(spec: dict) -> str:
    header = "# Written by `design solve`: the optimised design as a grasp scene (SI units).\n"
    return header + yaml.safe_dump(_plain(spec), sort_keys=False, default_flow_style=None,
                                   width=100)


def _plain(value):
    """numpy scalars to Python numbers, recursively."""
    if isinstance(value, dict):
        return {k: _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if hasattr(value, "item"):
        return value.item()
    return value
