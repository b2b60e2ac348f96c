"""The grasper in 3-D: drums, finger frames, and the bird's ellipsoid cut by a
finger's bending plane (thesis ch. IV, appendix B; docs/MODEL.md).

World frame Cw: origin on the conveyor surface midway between the two drum
axes, X along the conveyor's motion, Z up, Y towards the left drum. The
*right* drum's axis passes through (X_d, -d/2, 0); the left drum is its
mirror image about the XZ plane and turns the other way.

A finger on the right drum at angle φ (rad, about the drum axis, measured
from +X towards +Y, i.e. towards the bird) has its base at radius r_D and
height h along the axis. Its frame Cf3 is built by active rotations

    R = R_tilt · R_z(φ) · R_y(φ_y) · R_x(φ_x)

where R_tilt tilts the drum axis from vertical about the world Y axis. The
columns of R are the finger's x (the undeformed finger), y (its soft bending
direction; the planar model's plane is x-y) and z (its stiff direction). With φ_x = φ_y = 0 the finger
is radial and horizontal and bends in the horizontal plane, as in ch. III;
φ_y > 0 tilts it downwards (tip below base), φ_x = 90° turns its bending
plane vertical.

The convention is the thesis's own (docs/MODEL.md, "Finger layout"): φ is
chapter III's angular position ("ωt": 126° for Case 1 with the object
upstream, 180° at the start of the Table 3-4 pass), measured from the
conveyor's direction towards the bird; φ_y then φ_x are the rotations of
eq. B.21, [R3] = Rz^T Ry^T Rx^T with the passive matrices of eqs.
B.16a-B.18a, i.e. the active product above. Table 5-1's values enter as
printed.

The right drum turns clockwise seen from above, φ(t) = φ_i - ω t: on the
bird's side its fingers move downstream with the conveyor (§1.2, §4.3.3).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from design.physics.backend import ops, read_only
from design.physics.ellipse import Ellipse

MIRROR = np.diag([1.0, -1.0, 1.0])

# Every formula below takes numbers or CasADi symbols (design/physics/backend.py):
# the simulator evaluates them, the optimiser differentiates them.


def rot_x(a):
    xp = ops(a)
    c, s = xp.cos(a), xp.sin(a)
    return xp.matrix([[1, 0, 0], [0, c, -s], [0, s, c]])


def rot_y(a):
    xp = ops(a)
    c, s = xp.cos(a), xp.sin(a)
    return xp.matrix([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def rot_z(a):
    xp = ops(a)
    c, s = xp.cos(a), xp.sin(a)
    return xp.matrix([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def finger_frame(angle, height, radius, phi_x, phi_y, spacing, speed, t, x=0.0, tilt=0.0):
    """Base point (3,) and rotation (3, 3) of a right-drum finger at time t
    (see :class:`Drum`); any argument may be symbolic."""
    xp = ops(angle, height, radius, phi_x, phi_y, spacing, speed, t, x, tilt)
    phi = angle - speed * t
    r_tilt = rot_y(tilt)
    local = xp.vector([radius * xp.cos(phi), radius * xp.sin(phi), height])
    base = xp.vector([x, -spacing / 2, 0.0]) + r_tilt @ local
    return base, r_tilt @ rot_z(phi) @ rot_y(phi_y) @ rot_x(phi_x)


def section(semi_axes, center, pitch, base, R):
    """The plane z_f = 0 of a finger frame (base, R) cutting the ellipsoid of
    ``semi_axes`` (η, λ, γ) at ``center`` (3,) pitched by ``pitch``, as a
    conic in the frame's (x_f, y_f): centre u0 (2,) and matrix B (2, 2) with
    (u - u0)ᵀ B (u - u0) = 1; B is indefinite or the right-hand side ``rhs``
    ≤ 0 when the plane misses. Returns (u0, B, rhs).

    Points u of the plane are p_b = d + M u in body coordinates,
    d = R_bᵀ (base - c), M = R_bᵀ R[:, :2]; the quadric p_bᵀ Q p_b = 1 becomes
    uᵀ A u + 2 bᵀ u + c0 = 1 with A = Mᵀ Q M.
    """
    xp = ops(pitch, base, R, *center, *semi_axes)
    Rb = rot_y(pitch)
    d = Rb.T @ (base - xp.vector(list(center)))
    M = Rb.T @ R[:, :2]
    Q = xp.matrix([[1 / semi_axes[0] ** 2, 0, 0], [0, 1 / semi_axes[1] ** 2, 0],
                   [0, 0, 1 / semi_axes[2] ** 2]])
    A = M.T @ Q @ M
    b = M.T @ Q @ d
    c0 = d.T @ Q @ d
    det = A[0, 0] * A[1, 1] - A[0, 1] * A[1, 0]
    u0 = -xp.vector([A[1, 1] * b[0] - A[0, 1] * b[1], A[0, 0] * b[1] - A[1, 0] * b[0]]) / det
    rhs = 1.0 - (c0 + b.T @ u0)
    return u0, A / rhs, rhs


@dataclass(frozen=True)
class FingerMount:
    """Where and how a finger sits on a drum (right drum; the left mirrors it).

    ``angle`` φ_i (rad) at t = 0, ``height`` h (m) along the drum axis,
    ``radius`` r_D (m) of the drum at that height, mounting rotations
    ``phi_x`` and ``phi_y`` (rad).
    """

    angle: float
    height: float
    radius: float
    phi_x: float = 0.0
    phi_y: float = 0.0


@dataclass(frozen=True)
class Drum:
    """The right drum: axis through (x, -spacing/2, 0), tilted by ``tilt``
    (rad, about world Y, from vertical), turning at ``speed`` ω (rad/s)."""

    spacing: float
    speed: float
    x: float = 0.0
    tilt: float = 0.0

    @property
    def origin(self) -> np.ndarray:
        return np.array([self.x, -self.spacing / 2, 0.0])

    def turning(self, t) -> np.ndarray:
        """The rotation carrying drum-fixed vectors from t = 0 to t (s): -ω t
        about the drum's (tilted) axis; (3, 3), or (n, 3, 3) for n times.
        A finger's frame at t is (origin + M (base₀ - origin), M R₀)."""
        t = np.asarray(t, float)
        c, s = np.cos(self.speed * t), np.sin(self.speed * t)
        turn = np.zeros(t.shape + (3, 3))
        turn[..., 0, 0], turn[..., 0, 1], turn[..., 1, 0], turn[..., 1, 1] = c, s, -s, c
        turn[..., 2, 2] = 1.0
        if self.tilt == 0.0:
            return turn
        tilt = rot_y(self.tilt)
        return tilt @ turn @ tilt.T

    def frame(self, mount: FingerMount, t: float) -> tuple[np.ndarray, np.ndarray]:
        """Base point (3,) and rotation (3, 3) of a finger at time t (right drum)."""
        return finger_frame(mount.angle, mount.height, mount.radius, mount.phi_x, mount.phi_y,
                            self.spacing, self.speed, t, self.x, self.tilt)


def mirror_frame(base: np.ndarray, R: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The left drum's finger: the right one reflected about the XZ plane.

    A reflection is not a rotation; the bending axis (y) is reflected too and
    z is flipped so the frame stays right-handed: the left finger bends to
    the mirror image of where the right one bends.
    """
    Rm = MIRROR @ R
    Rm[:, 2] *= -1.0
    return MIRROR @ base, Rm


@dataclass(frozen=True)
class Ellipsoid:
    """The bird: semi-axes η (length, body x), λ (width, y), γ (height, z)
    in m, centre (3,) in m, pitch θ (rad) about the world Y axis."""

    eta: float
    lam: float
    gamma: float
    center: tuple[float, float, float]
    pitch: float = 0.0

    @cached_property
    def rotation(self) -> np.ndarray:
        """Body to world. Pitch convention X = x cos θ + z sin θ (MODEL.md §5):
        a positive θ turns the body's nose (+x) downwards."""
        return read_only(rot_y(self.pitch))

    @cached_property
    def matrix(self) -> np.ndarray:
        return read_only(np.diag([1 / self.eta ** 2, 1 / self.lam ** 2, 1 / self.gamma ** 2]))

    def level(self, points: np.ndarray) -> np.ndarray:
        """< 0 inside, 0 on the surface; points shape (3, ...)."""
        p = np.einsum("ji,j...->i...", self.rotation,
                      points - np.asarray(self.center).reshape(3, *([1] * (points.ndim - 1))))
        return np.einsum("i...,ii,i...->...", p, self.matrix, p) - 1.0

    def section(self, base: np.ndarray, R: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
        """The plane z_f = 0 of a finger frame cutting the ellipsoid, as a conic
        in that frame's (x_f, y_f): (centre, matrix, rhs), see :func:`section`."""
        return section((self.eta, self.lam, self.gamma), self.center, self.pitch,
                       np.asarray(base, float), R)

    def cut(self, base: np.ndarray, R: np.ndarray) -> Ellipse | None:
        """The ellipse in which the plane z_f = 0 of a finger frame cuts the
        ellipsoid, in that frame's (x_f, y_f) coordinates; None if it misses
        (see :func:`section`)."""
        u0, B, rhs = self.section(base, R)
        return Ellipse.from_conic(u0, B) if rhs > 0.0 else None

    def lowest_point(self) -> tuple[float, float]:
        """(X offset ahead of the centre, depth D below it) of the lowest point
        of the pitched ellipsoid's XZ section (MODEL.md §5; thesis 4.33-4.35)."""
        return lowest_point(self.eta, self.gamma, self.pitch)


def lowest_point(eta, gamma, pitch):
    """Offset ahead of the centre and depth D = sqrt(γ² cos²θ + η² sin²θ) of
    the lowest point of an ellipse (η along x, γ along z) pitched by θ."""
    xp = ops(eta, gamma, pitch)
    c, s = xp.cos(pitch), xp.sin(pitch)
    D = xp.sqrt(gamma ** 2 * c ** 2 + eta ** 2 * s ** 2)
    return (eta ** 2 - gamma ** 2) * s * c / D, D
