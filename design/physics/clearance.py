"""How far a straight finger passes from a resting object: the thesis's
design picture of §5.1 (Figure 5-3), the transverse section of the object
with the fingers drawn at several tilt angles.

A finger faces the object when its drum angle is π/2: it then points at the
conveyor's centre line and, with an untilted drum, lies in the transverse
plane X = X_base. The object rests on the belt (centre height γ) with its
centre in that plane, so the nearest point of the object to the finger lies
in the same plane (the ellipsoid is symmetric about it), on the section
ellipse with semi-axes λ (along Y) and γ (along Z). Lengths in m, angles in
rad.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from scipy.optimize import brentq, minimize_scalar

from design.physics.kinematics import Drum, FingerMount

#: parameter samples on the section ellipse before the nearest one is refined
SAMPLES = 720


def facing(drum: Drum, mount: FingerMount, length: float) -> tuple[np.ndarray, np.ndarray]:
    """The straight finger's base and tip (Y, Z; m) when it faces the object."""
    if drum.tilt != 0.0:
        raise ValueError("the transverse clearance needs an untilted drum")
    base, R = drum.frame(mount, (mount.angle - np.pi / 2) / drum.speed)
    tip = base + length * R[:, 0]
    return base[1:], tip[1:]


def _to_segment(points: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Distances (m) from points (2, n) to the segment a-b."""
    ab = b - a
    s = np.clip(((points.T - a) @ ab) / (ab @ ab), 0.0, 1.0)
    return np.linalg.norm(points.T - (a + np.outer(s, ab)), axis=1)


def clearance(drum: Drum, mount: FingerMount, length: float, lam: float, gamma: float
              ) -> float:
    """Distance (m) from the straight finger facing the object to the resting
    object's transverse section (semi-axes ``lam``, ``gamma``, centre at
    height ``gamma`` under the conveyor's centre line); negative when the
    finger enters it (then minus the depth of the finger's deepest point)."""
    a, b = facing(drum, mount, length)
    centre = np.array([0.0, gamma])
    scale = np.array([lam, gamma])
    s = np.linspace(0.0, 1.0, 201)
    inner = np.linalg.norm((a + np.outer(s, b - a) - centre) / scale, axis=1)
    if inner.min() < 1.0:                 # depth of the deepest point, along the radius
        k = int(np.argmin(inner))
        p = a + s[k] * (b - a) - centre
        return -float(np.linalg.norm(p) * (1.0 / inner[k] - 1.0))

    def gap(t: float) -> float:
        return float(_to_segment((centre + scale * np.array([np.cos(t), np.sin(t)]))[:, None],
                                 a, b)[0])

    t = np.linspace(-np.pi, np.pi, SAMPLES, endpoint=False)
    d = _to_segment(centre[:, None] + scale[:, None] * np.vstack([np.cos(t), np.sin(t)]), a, b)
    k = int(np.argmin(d))
    step = 2 * np.pi / SAMPLES
    return float(minimize_scalar(gap, bounds=(t[k] - step, t[k] + step), method="bounded",
                                 options={"xatol": 1e-10}).fun)


def matching_tilt(drum: Drum, mount: FingerMount, length: float, target: float, lam: float,
                  gamma: float, bracket: tuple[float, float] = (np.radians(-60.0), 0.0)
                  ) -> float:
    """The finger's φy (rad) at which it clears the object by ``target`` (m),
    searched in ``bracket`` (more negative φy tips the finger up)."""
    def excess(phi_y: float) -> float:
        return clearance(drum, replace(mount, phi_y=phi_y), length, lam, gamma) - target

    ends = [excess(a) for a in bracket]
    if ends[0] * ends[1] > 0:
        raise ValueError(f"no tilt in [{np.degrees(bracket[0]):g}, {np.degrees(bracket[1]):g}] "
                         f"deg clears the object by {1e3 * target:g} mm: the clearance spans "
                         f"{1e3 * (ends[0] + target):.1f} to {1e3 * (ends[1] + target):.1f} mm")
    return float(brentq(excess, *bracket, xtol=1e-9))
