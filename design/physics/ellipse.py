"""The object's cross-section: an ellipse in a plane, and the drum/finger frames.

Frames (MODEL.md §3): world Cw at the drum centre; the finger base sits at
radius r and angle φ, and the finger frame Cf has its origin there with x_f
along (cos φ, sin φ), y_f along (-sin φ, cos φ).

The ellipse has semi-axes ``a`` (along its own x_b) and ``b``, centre
``center`` and orientation ``theta`` (rad, x_b from the frame's x axis). Its
*level function* f(P) = (P - c)^T B (P - c) - 1 with B = R diag(1/a², 1/b²) R^T
is dimensionless, negative inside, zero on the curve; expanded it is the
thesis's conic b1 x² + b2 y² + 2 b3 x y + 2 b4 x + 2 b5 y + b6 (eq. 3.6).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import casadi as ca
import numpy as np

from design.physics.backend import read_only


def rotation(angle: float) -> np.ndarray:
    """2x2 rotation by ``angle`` (rad)."""
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, -s], [s, c]])


@dataclass(frozen=True)
class Ellipse:
    """An ellipse: semi-axes a, b (m), centre (m), orientation theta (rad)."""

    a: float
    b: float
    center: tuple[float, float]
    theta: float = 0.0

    @staticmethod
    def from_conic(center, B) -> "Ellipse":
        """The ellipse (u - c)ᵀ B (u - c) = 1 (B positive definite): semi-axes
        1/sqrt of B's eigenvalues, the larger first; θ from the first's
        eigenvector."""
        vals, vecs = np.linalg.eigh(B)
        axes = 1.0 / np.sqrt(vals)
        theta = float(np.arctan2(vecs[1, 0], vecs[0, 0]))
        return Ellipse(float(axes[0]), float(axes[1]), (float(center[0]), float(center[1])), theta)

    @property
    def params(self) -> np.ndarray:
        """[cx, cy, theta, a, b], the order :func:`level_casadi` expects."""
        return np.array([self.center[0], self.center[1], self.theta, self.a, self.b])

    def in_frame(self, origin: np.ndarray, angle: float) -> "Ellipse":
        """The same ellipse seen from a frame at ``origin`` rotated by ``angle``."""
        c = rotation(-angle) @ (np.asarray(self.center, float) - np.asarray(origin, float))
        return Ellipse(self.a, self.b, (float(c[0]), float(c[1])), self.theta - angle)

    def mirrored(self) -> "Ellipse":
        """Mirror image about the frame's x axis (y -> -y)."""
        return Ellipse(self.a, self.b, (self.center[0], -self.center[1]), -self.theta)

    def shifted(self, dx: float, dy: float) -> "Ellipse":
        return Ellipse(self.a, self.b, (self.center[0] + dx, self.center[1] + dy), self.theta)

    @cached_property
    def matrix(self) -> np.ndarray:
        R = rotation(self.theta)
        return read_only(R @ np.diag([1 / self.a ** 2, 1 / self.b ** 2]) @ R.T)

    def level(self, x, y) -> np.ndarray:
        """f(x, y): < 0 inside, 0 on the ellipse, > 0 outside (dimensionless)."""
        d = np.stack([np.asarray(x, float) - self.center[0], np.asarray(y, float) - self.center[1]])
        return np.einsum("i...,ij,j...->...", d, self.matrix, d) - 1.0

    def gradient(self, x, y) -> np.ndarray:
        """∇f (1/m), shape (2, ...); points outwards."""
        d = np.stack([np.asarray(x, float) - self.center[0], np.asarray(y, float) - self.center[1]])
        return 2 * np.einsum("ij,j...->i...", self.matrix, d)

    def conic(self) -> dict:
        """The thesis's coefficients b1..b6 of eq. (3.6) (same curve, same sign)."""
        B, c = self.matrix, np.asarray(self.center)
        lin = -B @ c
        return {"b1": B[0, 0], "b2": B[1, 1], "b3": B[0, 1], "b4": lin[0], "b5": lin[1],
                "b6": float(c @ B @ c - 1.0)}

    def point(self, t) -> np.ndarray:
        """Points at parameter t (rad): c + R (a cos t, b sin t); shape (2, ...)."""
        t = np.asarray(t, float)
        local = np.stack([self.a * np.cos(t), self.b * np.sin(t)])
        return np.asarray(self.center)[:, None].reshape(2, *([1] * t.ndim)) + \
            np.einsum("ij,j...->i...", rotation(self.theta), local)

    def distance_outside(self, x, y) -> np.ndarray:
        """Approximate signed distance (m) from the curve, < 0 inside: f / |∇f|."""
        g = self.gradient(x, y)
        return self.level(x, y) / np.maximum(np.hypot(g[0], g[1]), 1e-300)

    def y_range_at(self, x) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Lower and upper y of the ellipse on the vertical line at ``x``, and
        whether the line meets it at all."""
        B, c = self.matrix, np.asarray(self.center)
        dx = np.asarray(x, float) - c[0]
        # B11 dy² + 2 B01 dx dy + (B00 dx² - 1) = 0
        qa, qb, qc = B[1, 1], 2 * B[0, 1] * dx, B[0, 0] * dx ** 2 - 1
        disc = qb ** 2 - 4 * qa * qc
        meets = disc >= 0
        root = np.sqrt(np.maximum(disc, 0.0))
        return c[1] + (-qb - root) / (2 * qa), c[1] + (-qb + root) / (2 * qa), meets

    def x_range(self) -> tuple[float, float]:
        """Smallest and largest x of the ellipse."""
        half = np.sqrt((self.a * np.cos(self.theta)) ** 2 + (self.b * np.sin(self.theta)) ** 2)
        return self.center[0] - half, self.center[0] + half


def level_casadi(x, y, q):
    """f(x, y) for ellipse parameters q = [cx, cy, theta, a, b] (CasADi or numpy)."""
    dx, dy = x - q[0], y - q[1]
    c, s = ca.cos(q[2]), ca.sin(q[2])
    u = c * dx + s * dy          # coordinates in the ellipse's own axes
    v = -s * dx + c * dy
    return (u / q[3]) ** 2 + (v / q[4]) ** 2 - 1


def gradient_casadi(x, y, q):
    """∇f for ellipse parameters q (CasADi), as a 2-vector (1/m)."""
    dx, dy = x - q[0], y - q[1]
    c, s = ca.cos(q[2]), ca.sin(q[2])
    u, v = c * dx + s * dy, -s * dx + c * dy
    gu, gv = 2 * u / q[3] ** 2, 2 * v / q[4] ** 2
    return ca.vertcat(c * gu - s * gv, s * gu + c * gv)


def level_conic(x, y, q):
    """f(x, y) for a conic q = [cx, cy, B00, B01, B11]: (p - c)ᵀ B (p - c) - 1."""
    dx, dy = x - q[0], y - q[1]
    return q[2] * dx ** 2 + 2 * q[3] * dx * dy + q[4] * dy ** 2 - 1


def gradient_conic(x, y, q):
    """∇f for a conic q (CasADi), as a 2-vector (1/m)."""
    dx, dy = x - q[0], y - q[1]
    return ca.vertcat(2 * (q[2] * dx + q[3] * dy), 2 * (q[3] * dx + q[4] * dy))
