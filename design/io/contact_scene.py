"""Contact scenes (``kind: contact``): one finger on a drum against an ellipse.

.. code-block:: yaml

    kind: contact
    finger: models/fingers/thesis_nonuniform_soft.yaml   # or inline
    drum: {radius: 0.0825}
    finger_angle: 126 deg            # φ of the finger base; a list = a sequence of poses
    object: {semi_axes: [0.0991, 0.0673], center: [-0.1016, 0.184], orientation: 0}
    friction: 0.6
    sliding: auto                    # push | pull | auto
    motion: {drum_speed: 20 rpm, object_velocity: [0.508, 0]}
    solver: {method: robust}         # thesis-1 | thesis-2 | robust; options per method

``object.center`` may be a list of centres, one per pose; a single angle or
centre is used for every pose.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from design.io.fingers import read_finger
from design.io.reader import Reader, join
from design.physics.beam import Finger
from design.physics.contact import SIDES, FingerPose, Motion
from design.physics.ellipse import Ellipse
from design.solvers.contact import CONTACT_METHODS, CONTACT_OPTIONS, DEFAULT_CONTACT_METHOD

SLIDING = (*SIDES, "auto")


@dataclass(frozen=True)
class ContactScene:
    """A finger, its poses, the object at each pose, and how to solve."""

    name: str
    finger: Finger
    poses: tuple[FingerPose, ...]
    objects: tuple[Ellipse, ...]
    friction: float
    sliding: str
    motion: Motion | None
    method: str = DEFAULT_CONTACT_METHOD
    options: dict = field(default_factory=dict)
    description: str = ""


def read_solver_options(reader: Reader, data: dict, field_name: str, methods: dict,
                        options: dict, default: str) -> tuple[str | None, dict]:
    """``solver: {method: ..., <method options>}`` with per-method option checks."""
    if field_name not in data:
        return default, {}
    spec = reader.mapping(data[field_name], field_name,
                          optional=("method", *sorted({k for o in options.values() for k in o})))
    if spec is None:
        return None, {}
    method = reader.choice(spec, "method", field_name, methods, default=default)
    if method is None:
        return None, {}
    out = {}
    for key in spec:
        if key == "method":
            continue
        if key not in options[method]:
            reader.add(join(field_name, key), f"not an option of method '{method}' "
                                              f"(its options: {', '.join(options[method])})")
            continue
        arg, kind, lo, hi = options[method][key]
        if kind == "int":
            value = reader.integer(spec, key, field_name, lo=lo, hi=hi)
        elif kind == "bool":
            value = reader.boolean(spec, key, field_name)
        else:
            value = reader.quantity(spec, key, field_name, "dimensionless", lo=lo, hi=hi)
        if value is not None:
            out[arg] = value
    return method, out


def read_motion(reader: Reader, data: dict, field_name: str) -> Motion | None:
    spec = reader.mapping(data[field_name], field_name, required=("drum_speed",),
                          optional=("object_velocity", "object_spin"))
    if spec is None:
        return None
    omega = reader.quantity(spec, "drum_speed", field_name, "angular_speed")
    vel = reader.vectors(spec, "object_velocity", field_name, "speed", default=[(0.0, 0.0)])
    spin = reader.quantity(spec, "object_spin", field_name, "angular_speed", default=0.0)
    if omega is None or vel is None or spin is None:
        return None
    if len(vel) != 1:
        reader.add(join(field_name, "object_velocity"), "one velocity [vx, vy], not a list")
        return None
    return Motion(omega, vel[0], spin)


def read_contact(reader: Reader, data: dict, base_dir: Path, name: str) -> ContactScene | None:
    finger = read_finger(reader, data["finger"], "finger", base_dir) if "finger" in data else None
    drum = reader.mapping(data.get("drum"), "drum", required=("radius",)) if "drum" in data else None
    radius = reader.quantity(drum, "radius", "drum", "length", lo=0.0) if drum is not None else None
    angles = reader.quantities(data, "finger_angle", "", "angle", lo=-4 * np.pi, hi=4 * np.pi)
    obj = reader.mapping(data.get("object"), "object", required=("semi_axes", "center"),
                         optional=("orientation",)) if "object" in data else None
    axes = centers = orientation = None
    if obj is not None:
        axes = reader.vectors(obj, "semi_axes", "object", "length")
        if axes is not None and (len(axes) != 1 or min(axes[0]) <= 0):
            reader.add("object.semi_axes", "two positive lengths [a, b] (m), a along the "
                                           "object's own x axis")
            axes = None
        centers = reader.vectors(obj, "center", "object", "length")
        orientation = reader.quantity(obj, "orientation", "object", "angle", default=0.0)
    friction = reader.quantity(data, "friction", "", "dimensionless", lo=0.0, hi=10.0)
    sliding = reader.choice(data, "sliding", "", SLIDING, default="auto")
    motion = read_motion(reader, data, "motion") if "motion" in data else None
    method, options = read_solver_options(reader, data, "solver", CONTACT_METHODS,
                                          CONTACT_OPTIONS, DEFAULT_CONTACT_METHOD)
    if angles is not None and centers is not None:
        n = max(len(angles), len(centers))
        if len(angles) not in (1, n) or len(centers) not in (1, n):
            reader.add("object.center", f"{len(centers)} centres for {len(angles)} finger "
                                        f"angles: give one of each, or equally many")
    if method in ("thesis-1", "thesis-2") and sliding == "auto":
        reader.add("sliding", f"the thesis's algorithms need the side set by hand: push or pull "
                              f"(method {method})")
    if not reader.ok or None in (finger, radius, angles, axes, centers, orientation, friction,
                                 sliding, method):
        return None
    n = max(len(angles), len(centers))
    angles = angles * n if len(angles) == 1 else angles
    centers = centers * n if len(centers) == 1 else centers
    poses = tuple(FingerPose(radius, a) for a in angles)
    objects = tuple(Ellipse(axes[0][0], axes[0][1], c, orientation) for c in centers)
    return ContactScene(name, finger, poses, objects, friction, sliding, motion, method, options,
                        data.get("description", ""))
