"""Grasp scenes (``kind: grasp``) and the models they reference: graspers,
birds and conveyor profiles (each inline or a file under ``models/``).

.. code-block:: yaml

    kind: grasp
    grasper: models/graspers/thesis_table_5_1.yaml
    finger_models: {lower: models/fingers/thesis_nonuniform_soft.yaml}   # optional
    mounts: {"3": {phi_x: 60 deg}}     # optional: change a designed finger (every set)
    bird: models/birds/mean_1_80kg.yaml
    conveyor: models/conveyors/constant_0457.yaml     # or {speed: 0.457, ...}
    drum_speed: 20 rpm
    start: {X: -0.457}                                  # centre X at t = 0 (m)
    friction: {finger: 0.4, conveyor: 0.4}             # and belt: finger-belt (default: conveyor)
    belt: {width: 0.15 m, slots: ["5"]}                # optional (default: solid, no slots)
    legs: {stiffness: 30, damping: 1.5}                 # N/m, N s/m
    duration: 2.0
    solver: {integrator: adaptive}                      # adaptive | bdf4, and options
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from design.io.fingers import read_finger
from design.io.files import read_model
from design.io.reader import Reader, join
from design.physics.beam import Finger
from design.physics.belt import Belt
from design.physics.bird import Bird, Conveyor, Legs
from design.physics.grasper import GraspFinger, Grasper, mounted_sets
from design.physics.kinematics import FingerMount
from design.solvers.grasp.fingers import FINGER_MODELS
from design.solvers.grasp.integrate import INTEGRATORS, STEPPERS, IntegratorSettings
from design.solvers.grasp.simulation import GraspSetup

_MODEL_KEYS = ("kind", "name", "description", "source", "note")


def _grasper(reader: Reader, data: object, field_name: str, base_dir: Path,
             default_name: str) -> Grasper | None:
    spec = reader.mapping(data, field_name, required=("spacing", "fingers"),
                          optional=(*_MODEL_KEYS, "tilt", "x", "sets", "finger_models"))
    if spec is None:
        return None
    spacing = reader.quantity(spec, "spacing", field_name, "length", lo=0.0, lo_open=True)
    tilt = reader.quantity(spec, "tilt", field_name, "angle", lo=-1.5, hi=1.5, default=0.0)
    x = reader.quantity(spec, "x", field_name, "length", default=0.0)
    sets = reader.integer(spec, "sets", field_name, lo=1, hi=12, default=1)
    models = read_finger_models(reader, spec, join(field_name, "finger_models"), base_dir)
    fingers = []
    raw = spec.get("fingers")
    if not isinstance(raw, list) or not raw:
        reader.add(join(field_name, "fingers"), "a non-empty list of fingers")
        return None
    for i, item in enumerate(raw):
        f = join(join(field_name, "fingers"), i)
        fs = reader.mapping(item, f, required=("length", "height", "drum_radius", "angle"),
                            optional=("name", "group", "phi_x", "phi_y", "finger"))
        if fs is None:
            continue
        length = reader.quantity(fs, "length", f, "length", lo=0.0, lo_open=True)
        height = reader.quantity(fs, "height", f, "length")
        radius = reader.quantity(fs, "drum_radius", f, "length", lo=0.0, lo_open=True)
        angle = reader.quantity(fs, "angle", f, "angle")
        phi_x = reader.quantity(fs, "phi_x", f, "angle", lo=-3.1416, hi=3.1416, default=0.0)
        phi_y = reader.quantity(fs, "phi_y", f, "angle", lo=-1.5708, hi=1.5708, default=0.0)
        group = reader.text(fs, "group", f, default="")
        name = str(fs.get("name", i + 1))
        model = read_finger(reader, fs["finger"], join(f, "finger"), base_dir) if "finger" in fs \
            else (models or {}).get(group)
        if model is None and "finger" not in fs:
            reader.add(join(f, "group"), f"no finger model for group '{group}' (give "
                                         f"finger_models.{group or '<group>'} or the finger's "
                                         f"own 'finger')")
        if None in (length, height, radius, angle, phi_x, phi_y, model):
            continue
        fingers.append(GraspFinger(name, replace(model, length=length),
                                   FingerMount(angle, height, radius, phi_x, phi_y), group))
    if not reader.ok or spacing is None or sets is None:
        return None
    return Grasper(mounted_sets(fingers, sets), spacing, tilt, x,
                   spec.get("name", default_name), sets)


def read_finger_models(reader: Reader, data: dict, field_name: str, base_dir: Path
                       ) -> dict[str, Finger] | None:
    """``finger_models: {group: finger}`` (files or inline)."""
    key = field_name.rsplit(".", 1)[-1]
    if key not in data:
        return None
    spec = data[key]
    if not isinstance(spec, dict):
        reader.add(field_name, "a mapping of finger group to finger model")
        return None
    out = {}
    for group, value in spec.items():
        finger = read_finger(reader, value, join(field_name, str(group)), base_dir)
        if finger is not None:
            out[str(group)] = finger
    return out


def _bird(reader: Reader, data: object, field_name: str, base_dir: Path,
          default_name: str) -> Bird | None:
    spec = reader.mapping(data, field_name, required=("semi_axes", "mass"),
                          optional=(*_MODEL_KEYS, "inertia_y"))
    if spec is None:
        return None
    axes = reader.vectors(spec, "semi_axes", field_name, "length", size=3)
    mass = reader.quantity(spec, "mass", field_name, "mass", lo=0.0, lo_open=True)
    inertia = reader.quantity(spec, "inertia_y", field_name, "inertia", lo=0.0, lo_open=True,
                              default=None)
    if axes is None or mass is None:
        return None
    eta, lam, gamma = axes[0]
    if min(eta, lam, gamma) <= 0:
        reader.add(join(field_name, "semi_axes"), "three positive lengths [η, λ, γ] (m)")
        return None
    if inertia is None:            # solid ellipsoid about its width axis
        inertia = mass * (eta ** 2 + gamma ** 2) / 5
    return Bird(eta, lam, gamma, mass, inertia, spec.get("name", default_name))


def _conveyor(reader: Reader, data: object, field_name: str, base_dir: Path,
              default_name: str) -> Conveyor | None:
    spec = reader.mapping(data, field_name, required=("speed",),
                          optional=(*_MODEL_KEYS, "final_speed", "rate", "start_time",
                                    "start_position"))
    if spec is None:
        return None
    speed = reader.quantity(spec, "speed", field_name, "speed", lo=0.0)
    final = reader.quantity(spec, "final_speed", field_name, "speed", lo=0.0, default=None)
    rate = reader.quantity(spec, "rate", field_name, "acceleration", lo=0.0, lo_open=True,
                           default=2.0)
    t0 = reader.quantity(spec, "start_time", field_name, "time", lo=0.0, default=None)
    x0 = reader.quantity(spec, "start_position", field_name, "length", default=None)
    if t0 is not None and x0 is not None:
        reader.add(join(field_name, "start_time"), "give start_time or start_position, not both")
    if final is not None and t0 is None and x0 is None:
        reader.add(join(field_name, "final_speed"), "a deceleration needs start_time or "
                                                    "start_position")
    if speed is not None and final is not None and final > speed:
        reader.add(join(field_name, "final_speed"), f"{final:g} m/s is above the starting speed "
                                                    f"{speed:g} m/s: only decelerations")
    if not reader.ok or speed is None:
        return None
    return Conveyor(speed, final, rate, t0, x0)


def read_grasper(reader, value, field_name, base_dir):
    return read_model(reader, value, field_name, base_dir, "grasper", _grasper)


def read_bird(reader, value, field_name, base_dir):
    return read_model(reader, value, field_name, base_dir, "bird", _bird)


def read_conveyor(reader, value, field_name, base_dir):
    return read_model(reader, value, field_name, base_dir, "conveyor", _conveyor)


MODEL_READERS = {"grasper": _grasper, "bird": _bird, "conveyor": _conveyor}


@dataclass(frozen=True)
class GraspSettings:
    """Solver settings of a grasp run."""

    integrator: IntegratorSettings = field(default_factory=IntegratorSettings)
    #: collocation intervals of each finger's contact beam
    contact_nodes: int = 6
    #: skip contact solves outside the fingers' reach windows
    reach_filter: bool = True


@dataclass(frozen=True)
class GraspScene(GraspSetup):
    """A grasp scene file: the physical system (:class:`GraspSetup`, SI) with
    its name, description and the simulator's settings."""

    name: str = ""
    settings: GraspSettings = field(default_factory=GraspSettings)
    description: str = ""


def read_grasp_settings(reader: Reader, data: dict, field_name: str) -> GraspSettings | None:
    if field_name not in data:
        return GraspSettings()
    spec = reader.mapping(data[field_name], field_name,
                          optional=("integrator", "rtol", "atol", "max_step", "stepper", "step",
                                    "contact_nodes", "reach_filter", "max_wall_time",
                                    "max_local_error"))
    if spec is None:
        return None
    d = IntegratorSettings()
    integ = reader.choice(spec, "integrator", field_name, INTEGRATORS, default=d.integrator)
    rtol = reader.quantity(spec, "rtol", field_name, "dimensionless", lo=1e-12, hi=0.1,
                           default=d.rtol)
    atol = reader.quantity(spec, "atol", field_name, "length", lo=1e-14, hi=0.01, default=d.atol)
    max_step = reader.quantity(spec, "max_step", field_name, "time", lo=1e-6, hi=0.1,
                               default=d.max_step)
    stepper = reader.choice(spec, "stepper", field_name, STEPPERS, default=d.stepper)
    step = reader.quantity(spec, "step", field_name, "time", lo=1e-5, hi=0.1, default=d.step)
    local = reader.quantity(spec, "max_local_error", field_name, "length", lo=0.0, lo_open=True,
                            hi=1.0, default=d.max_local_error)
    nodes = reader.integer(spec, "contact_nodes", field_name, lo=2, hi=64, default=6)
    reach = reader.boolean(spec, "reach_filter", field_name, default=True)
    budget = reader.quantity(spec, "max_wall_time", field_name, "time", lo=0.0, lo_open=True,
                             default=None) if "max_wall_time" in spec else None
    if None in (integ, rtol, atol, max_step, stepper, step, local, nodes, reach) or \
            ("max_wall_time" in spec and budget is None):
        return None
    return GraspSettings(IntegratorSettings(integ, rtol, atol, max_step, stepper, step, budget,
                                            local), nodes, reach)


MOUNT_FIELDS = ("angle", "phi_x", "phi_y")


def _remounted(reader: Reader, grasper: Grasper, value: object) -> Grasper:
    """The grasper with ``mounts: {finger: {angle|phi_x|phi_y: value}}`` applied
    to every set's copy of each named (designed) finger; angle is set a's."""
    names = sorted({gf.design_name for gf in grasper.fingers})
    spec = reader.mapping(value, "mounts", optional=tuple(value) if isinstance(value, dict) else ())
    if spec is None:
        return grasper
    changes = {}
    for name, item in spec.items():
        path = join("mounts", str(name))
        if str(name) not in names:
            reader.add(path, f"the grasper has no finger '{name}' (it has {', '.join(names)})")
            continue
        fields = reader.mapping(item, path, optional=MOUNT_FIELDS)
        if fields is not None:
            values = {k: reader.quantity(fields, k, path, "angle", lo=-2 * np.pi, hi=2 * np.pi)
                      for k in fields}
            changes[str(name)] = {k: v for k, v in values.items() if v is not None}
    return grasper.remounted(changes)


def read_belt(reader: Reader, data: dict, grasper: Grasper | None) -> Belt | None:
    """``belt: {width: .., slots: [finger, ...]}`` (design/physics/belt.py);
    absent: a solid belt."""
    if "belt" not in data:
        return Belt()
    spec = reader.mapping(data["belt"], "belt", optional=("width", "slots"))
    if spec is None:
        return None
    width = reader.quantity(spec, "width", "belt", "length", lo=0.0, lo_open=True,
                            default=np.inf)
    slots = spec.get("slots", [])
    if not isinstance(slots, list):
        reader.add(join("belt", "slots"), f"a list of finger names, not {slots!r}")
        return None
    names = sorted({gf.design_name for gf in grasper.fingers}) if grasper is not None else None
    for slot in slots:
        if names is not None and str(slot) not in names:
            reader.add(join("belt", "slots"), f"the grasper has no finger '{slot}' (it has "
                                              f"{', '.join(names)})")
    if width is None or not reader.ok:
        return None
    return Belt(width, frozenset(str(x) for x in slots))


def read_grasp(reader: Reader, data: dict, base_dir: Path, name: str) -> GraspScene | None:
    grasper = read_grasper(reader, data["grasper"], "grasper", base_dir) \
        if "grasper" in data else None
    models = read_finger_models(reader, data, "finger_models", base_dir)
    bird = read_bird(reader, data["bird"], "bird", base_dir) if "bird" in data else None
    conveyor = read_conveyor(reader, data["conveyor"], "conveyor", base_dir) \
        if "conveyor" in data else None
    omega = reader.quantity(data, "drum_speed", "", "angular_speed", lo=0.0, lo_open=True)
    start = reader.mapping(data["start"], "start", required=("X",)) if "start" in data else None
    x0 = reader.quantity(start, "X", "start", "length") if start is not None else None
    fr = reader.mapping(data.get("friction", {}), "friction",
                        optional=("finger", "conveyor", "belt"))
    mu_f = reader.quantity(fr or {}, "finger", "friction", "dimensionless", lo=0.0, hi=10.0,
                           default=0.4)
    mu_c = reader.quantity(fr or {}, "conveyor", "friction", "dimensionless", lo=0.0, hi=10.0,
                           default=0.4)
    mu_b = reader.quantity(fr or {}, "belt", "friction", "dimensionless", lo=0.0, hi=10.0,
                           default=None)
    lg = reader.mapping(data.get("legs", {}), "legs", optional=("stiffness", "damping"))
    k = reader.quantity(lg or {}, "stiffness", "legs", "spring_stiffness", lo=0.0,
                        default=Legs().stiffness)
    c = reader.quantity(lg or {}, "damping", "legs", "damping", lo=0.0, default=Legs().damping)
    duration = reader.quantity(data, "duration", "", "time", lo=0.0, lo_open=True, hi=60.0)
    finger_model = reader.choice(data, "finger_model", "", FINGER_MODELS, default="planar")
    settings = read_grasp_settings(reader, data, "solver")
    if grasper is not None and "mounts" in data:
        grasper = _remounted(reader, grasper, data["mounts"])
    belt = read_belt(reader, data, grasper)
    if grasper is not None and models:
        grasper = grasper.with_models(models)
        unknown = set(models) - {gf.group for gf in grasper.fingers}
        for group in sorted(unknown):
            reader.add(join("finger_models", group), f"no finger of the grasper is in group "
                                                     f"'{group}'")
    if not reader.ok or None in (grasper, bird, conveyor, omega, x0, mu_f, mu_c, k, c, duration,
                                 settings, finger_model, belt):
        return None
    return GraspScene(grasper, bird, conveyor, omega, x0, mu_f, mu_c, Legs(k, c), duration,
                      finger_model, belt, mu_b, name=name, settings=settings,
                      description=data.get("description", ""))
