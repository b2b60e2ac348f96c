"""One finger against the object's cross-section, in the finger's plane (thesis ch. III).

Conventions. The finger base is on the drum at radius r and angle φ (world
frame at the drum centre); the drum turns clockwise for ω > 0, φ = φ0 - ω t.
Forces are on the object unless named otherwise; the force on the finger is
F(-cos α, sin α) in the finger frame (as for the beam).

Two independent choices describe a frictional contact:

* the *side*: ``push`` when the object deflects the finger towards +y_f
  (the finger pushes the object along its sweep for ω > 0), ``pull`` when
  towards -y_f (thesis §4.3.3 defines push and pull this way);
* the *friction sense* on the finger: ``tipward`` (the thesis's eq. 3.7:
  α + ψ0 = π/2 + atan µ for push) or ``baseward``, opposite to the finger's
  sliding over the object's surface.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import brentq

from design.physics.ellipse import Ellipse, rotation

SIDES = {"push": 1, "pull": -1}
FRICTION_SENSES = {"tipward": 1, "baseward": -1, "none": 0}


@dataclass(frozen=True)
class FingerPose:
    """Where a finger's base is: drum radius (m) and angle φ (rad)."""

    radius: float
    angle: float

    @property
    def base(self) -> np.ndarray:
        """Base point in the world (drum-centre) frame, m."""
        return self.radius * np.array([np.cos(self.angle), np.sin(self.angle)])

    def to_world(self, x, y) -> np.ndarray:
        """Finger-frame points to world, shape (2, ...)."""
        pts = rotation(self.angle) @ np.stack([np.atleast_1d(x), np.atleast_1d(y)])
        return pts + self.base[:, None]

    def vector_to_world(self, v) -> np.ndarray:
        return rotation(self.angle) @ np.asarray(v, float)

    def view(self, ellipse: Ellipse) -> Ellipse:
        """A world-frame ellipse seen in this finger's frame."""
        return ellipse.in_frame(self.base, self.angle)


@dataclass(frozen=True)
class Motion:
    """Rates that decide the sliding direction: drum speed ω (rad/s, > 0
    clockwise), the object's velocity (m/s, world) and spin (rad/s)."""

    drum_speed: float
    object_velocity: tuple[float, float] = (0.0, 0.0)
    object_spin: float = 0.0


@dataclass(frozen=True)
class ContactSolution:
    """The quasi-static state of one finger at one pose.

    Positions in m, force in N, angles in rad. ``point``/``psi``/``alpha``
    are in the finger frame; ``shape_*`` cover the whole finger (the loaded
    part, then the straight rest). ``penetration`` is the deepest point of
    the finger inside the object (m, 0 when none, nan when not checked).
    """

    contact: bool
    force: float
    alpha: float
    arc_length: float
    point: tuple[float, float]
    psi: float
    tip_contact: bool
    side: str | None
    friction: str
    pose: FingerPose
    shape_s: np.ndarray
    shape_x: np.ndarray
    shape_y: np.ndarray
    converged: bool
    iterations: int = 0
    message: str = ""
    penetration: float = 0.0
    extras: dict = field(default_factory=dict)
    #: the finger's force on the belt in its plane (N, finger frame; None: not
    #: on the belt), its normal part, the tip where it acts, and how far the
    #: finger's deepest point lies below the belt (m) (design/solvers/contact/
    #: planar_belt.py)
    belt_force: np.ndarray | None = None
    belt_normal_force: float = 0.0
    belt_point: np.ndarray | None = None
    below_belt: float = 0.0

    @property
    def force_on_object_finger_frame(self) -> np.ndarray:
        """Force on the object in the finger frame, N (minus the force on the finger)."""
        return self.force * np.array([np.cos(self.alpha), -np.sin(self.alpha)])

    @property
    def force_vector(self) -> np.ndarray:
        """Force on the object in the world frame, N."""
        return self.pose.vector_to_world(self.force_on_object_finger_frame)

    @property
    def shape_points(self) -> np.ndarray:
        """The whole finger in its frame (3, n), z = 0: the planar finger stays in its plane."""
        return np.vstack([self.shape_x, self.shape_y, np.zeros_like(self.shape_x)])

    @property
    def point_world(self) -> np.ndarray:
        return self.pose.to_world(*self.point)[:, 0]

    @property
    def shape_world(self) -> np.ndarray:
        return self.pose.to_world(self.shape_x, self.shape_y)


def no_contact(pose: FingerPose, length: float, message: str, converged: bool = True,
               n: int = 2) -> ContactSolution:
    """The undeflected finger: nothing touches it."""
    s = np.linspace(0.0, length, n)
    return ContactSolution(False, 0.0, 0.0, 0.0, (np.nan, np.nan), 0.0, False, None, "none",
                           pose, s, s.copy(), np.zeros_like(s), converged, message=message)


def segment_overlap(ellipse: Ellipse, length: float) -> float:
    """min over the undeflected finger (0 ≤ x ≤ l, y = 0) of the level function;
    < 0 when the straight finger would pass through the object."""
    return straight_overlap(np.asarray(ellipse.center), ellipse.matrix, length)


def straight_overlap(center: np.ndarray, B: np.ndarray, length: float) -> float:
    """:func:`segment_overlap` of the conic (u - c)ᵀ B (u - c) = 1."""
    # f(x, 0) = B00 (x - cx)^2 + 2 B01 (x - cx) (-cy) + B11 cy^2 - 1: a parabola in x
    x_star = center[0] + B[0, 1] * center[1] / B[0, 0]
    dx = np.array([0.0, length, np.clip(x_star, 0.0, length)]) - center[0]
    dy = -center[1]
    return float(np.min(B[0, 0] * dx * dx + 2 * B[0, 1] * dx * dy + B[1, 1] * dy * dy) - 1.0)


def grazing(ellipse: Ellipse, length: float, side: int) -> tuple[float, float] | None:
    """How far the object must move to -side·y_f for the straight finger to
    just touch it, and where: (shift δ ≥ 0 in m, x of the touching point).

    For side = +1 the object lies towards -y_f and δ = max over the finger of
    the ellipse's upper boundary y_hi(x); for side = -1 the mirror. None when
    the finger's span does not reach the ellipse's x-range at all.
    """
    e = ellipse if side > 0 else ellipse.mirrored()
    x_lo, x_hi = e.x_range()
    lo, hi = max(0.0, x_lo), min(length, x_hi)
    if lo > hi:
        return None
    th, a, b = e.theta, e.a, e.b
    t_top = np.arctan2(b * np.cos(th), a * np.sin(th))
    x_top = e.center[0] + a * np.cos(t_top) * np.cos(th) - b * np.sin(t_top) * np.sin(th)
    x_g = float(np.clip(x_top, lo, hi))     # y_hi is concave in x
    y_top = e.y_range_at(x_g)[1]
    return float(y_top), x_g


def turned(ellipse: Ellipse, angle: float) -> Ellipse:
    """The ellipse turned by ``angle`` (rad, counter-clockwise) about the finger's base."""
    c = rotation(angle) @ np.asarray(ellipse.center, float)
    return Ellipse(ellipse.a, ellipse.b, (float(c[0]), float(c[1])), ellipse.theta + angle)


def swept_grazing(ellipse: Ellipse, length: float, side: int) -> tuple[float, float] | None:
    """How far the object must be turned about the finger's base, against the
    way it deflects the finger, for the straight finger to just touch it, and
    where: (turn γ in rad, x of the touching point), so that
    ``turned(ellipse, γ)`` touches the finger at (x, 0).

    The drum's own motion: turning keeps every distance from the base, so
    the object never passes over the base on its way. The object meets the
    disc of the finger's reach (r ≤ l) in a convex set, which subtends less
    than π from a base outside it; for side = +1 (object towards -y_f) γ is
    minus the largest polar angle of that set, for side = -1 minus the
    smallest. The touch is where the ray from the base is tangent to the
    ellipse, or the finger's tip if that tangent point lies beyond reach.
    None when the base is inside the object or the object is out of reach.
    """
    c = np.asarray(ellipse.center, float)
    q = rotation(-ellipse.theta) @ -c                    # the base in the ellipse's axes
    A, B = q[0] / ellipse.a, q[1] / ellipse.b
    rho = np.hypot(A, B)
    if rho <= 1.0 or segment_overlap(ellipse, length) >= 0.0:
        return None
    towards = np.arctan2(c[1], c[0])

    def polar(p):                                        # angle from the base, about `towards`
        return towards + _wrap(np.arctan2(p[1], p[0]) - towards)

    t_mid, spread = np.arctan2(B, A), np.arccos(1.0 / rho)
    tangents = ellipse.point(np.array([t_mid - spread, t_mid + spread])).T
    pick = np.argmax if side > 0 else np.argmin
    k = int(pick([polar(p) for p in tangents]))
    r_touch, phi_touch = float(np.hypot(*tangents[k])), float(polar(tangents[k]))
    if r_touch > length:
        # the object's edge within reach is where the ray from the base enters
        # it at r = l: one crossing between the finger (0, which meets the
        # object within reach) and the tangent direction
        def entry_beyond_reach(phi):
            d = np.array([np.cos(phi), np.sin(phi)])
            M = ellipse.matrix
            qa, qb, qc = d @ M @ d, -2 * d @ M @ c, c @ M @ c - 1.0
            r_in = (-qb - np.sqrt(max(qb * qb - 4 * qa * qc, 0.0))) / (2 * qa)
            return r_in - length
        phi_touch = float(brentq(entry_beyond_reach, *sorted((0.0, phi_touch)), xtol=1e-15))
        r_touch = length
    return -phi_touch, r_touch


def _wrap(angle: float) -> float:
    """``angle`` mapped into [-π, π)."""
    return float((angle + np.pi) % (2 * np.pi) - np.pi)
