"""A grasper: the fingers on the right drum (the left one mirrors them)."""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from design.physics.beam import Finger
from design.physics.kinematics import Drum, FingerMount


@dataclass(frozen=True)
class GraspFinger:
    """One finger: its beam (length and EI profile), where it is mounted, and
    its group (fingers of a group share a stiffness, e.g. ``upper``/``lower``)."""

    name: str
    finger: Finger
    mount: FingerMount
    group: str = ""


@dataclass(frozen=True)
class Grasper:
    """Fingers of the right drum, the drums' spacing (m, between axes), their
    axes' tilt from vertical (rad, about Y) and X position (m)."""

    fingers: tuple[GraspFinger, ...]
    spacing: float
    tilt: float = 0.0
    x: float = 0.0
    name: str = ""

    def drum(self, speed: float) -> Drum:
        return Drum(self.spacing, speed, self.x, self.tilt)

    def with_finger(self, index: int, finger: GraspFinger) -> "Grasper":
        fingers = list(self.fingers)
        fingers[index] = finger
        return replace(self, fingers=tuple(fingers))

    def describe(self) -> dict:
        return {"name": self.name, "spacing": self.spacing, "tilt": self.tilt, "x": self.x,
                "fingers": [{"name": f.name, "group": f.group, "length": f.finger.length,
                             "height": f.mount.height, "angle": f.mount.angle,
                             "drum_radius": f.mount.radius, "phi_x": f.mount.phi_x,
                             "phi_y": f.mount.phi_y, "stiffness": f.finger.stiffness.describe()}
                            for f in self.fingers]}


def spacing_rules(grasper: Grasper, lam: float, sigma_lam: float = 0.0) -> list[str]:
    """Design rules of §5.1 that the layout breaks (eq. 5.7: d ≥ λ + σ_λ,
    d ≥ l for every finger); empty when all hold. ``lam`` the bird's half
    width (m)."""
    broken = []
    if grasper.spacing < lam + sigma_lam:
        broken.append(f"drum spacing {grasper.spacing:g} m < λ + σ_λ = {lam + sigma_lam:g} m (5.7)")
    longest = max(f.finger.length for f in grasper.fingers)
    if grasper.spacing < longest:
        broken.append(f"drum spacing {grasper.spacing:g} m < finger length {longest:g} m (5.7)")
    return broken


def unit_vector(angle: float) -> np.ndarray:
    return np.array([np.cos(angle), np.sin(angle)])
