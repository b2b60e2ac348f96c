"""A grasper: the fingers on the right drum (the left one mirrors them)."""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from design.physics.beam import Finger
from design.physics.kinematics import Drum, FingerMount


@dataclass(frozen=True)
class GraspFinger:
    """One finger: its beam (length and EI profile), where it is mounted, and
    its group (fingers of a group share a stiffness, e.g. ``upper``/``lower``).

    On a drum with n finger sets (thesis eqs. 5.3-5.4) every designed finger
    is mounted n times, 2π/n apart: ``family`` names the designed finger
    (its layout variables) and ``phase`` (rad) is this copy's angle beyond
    the designed one.
    """

    name: str
    finger: Finger
    mount: FingerMount
    group: str = ""
    family: str = ""
    phase: float = 0.0

    @property
    def design_name(self) -> str:
        """The designed finger this one is a copy of (its own name if none)."""
        return self.family or self.name


@dataclass(frozen=True)
class Grasper:
    """Fingers of the right drum (every mounted copy), the drums' spacing
    (m, between axes), their axes' tilt from vertical (rad, about Y) and X
    position (m), and the number of finger sets around each drum."""

    fingers: tuple[GraspFinger, ...]
    spacing: float
    tilt: float = 0.0
    x: float = 0.0
    name: str = ""
    sets: int = 1

    def drum(self, speed: float) -> Drum:
        return Drum(self.spacing, speed, self.x, self.tilt)

    def with_models(self, models: dict[str, Finger]) -> "Grasper":
        """Every finger of a group in ``models`` (by group) made of that finger
        model, each keeping its own length."""
        return replace(self, fingers=tuple(
            replace(gf, finger=replace(models[gf.group], length=gf.finger.length))
            if gf.group in models else gf for gf in self.fingers))

    def remounted(self, changes: dict[str, dict[str, float]]) -> "Grasper":
        """Every set's copy of a designed finger (by design name) with its mount
        changed: ``{"3": {"phi_x": 1.05}}`` (rad; an angle is set a's)."""
        fingers = []
        for gf in self.fingers:
            change = dict(changes.get(gf.design_name, {}))
            if "angle" in change:
                change["angle"] += gf.phase
            fingers.append(replace(gf, mount=replace(gf.mount, **change)) if change else gf)
        return replace(self, fingers=tuple(fingers))

    def with_sets(self, sets: int) -> "Grasper":
        """The grasper with ``sets`` finger sets, 2π/sets apart, each the
        designed set (eqs. 5.3-5.4)."""
        designed = [replace(gf, name=gf.design_name, family="", phase=0.0)
                    for gf in self.fingers if gf.phase == 0.0]
        return replace(self, fingers=mounted_sets(designed, sets), sets=sets)

    def with_finger(self, index: int, finger: GraspFinger) -> "Grasper":
        fingers = list(self.fingers)
        fingers[index] = finger
        return replace(self, fingers=tuple(fingers))

    def describe(self) -> dict:
        return {"name": self.name, "spacing": self.spacing, "tilt": self.tilt, "x": self.x,
                "sets": self.sets, "fingers": [{"name": f.name, "group": f.group, "length": f.finger.length,
                             "height": f.mount.height, "angle": f.mount.angle,
                             "drum_radius": f.mount.radius, "phi_x": f.mount.phi_x,
                             "phi_y": f.mount.phi_y, "stiffness": f.finger.stiffness.describe()}
                            for f in self.fingers]}


def mounted_sets(fingers: list[GraspFinger], sets: int) -> tuple[GraspFinger, ...]:
    """Each designed finger mounted ``sets`` times, 2π/sets apart (thesis eqs.
    5.3-5.4: n finger sets around a drum); copies are named with a set
    letter, ``4a``, ``4b``, ...; one set keeps the designed names."""
    if sets == 1:
        return tuple(fingers)
    out = []
    for k in range(sets):
        phase = 2 * np.pi * k / sets
        for gf in fingers:
            out.append(replace(gf, name=f"{gf.name}{'abcdefghijkl'[k]}", family=gf.name,
                               phase=phase, mount=replace(gf.mount, angle=gf.mount.angle + phase)))
    return tuple(out)
