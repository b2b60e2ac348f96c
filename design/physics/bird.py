"""The bird on the conveyor: symmetric grasp dynamics (thesis §4.4, MODEL.md §5).

State y = (X, Z, θ, Ẋ, Ż, θ̇): centre position (m) and pitch (rad, positive
nose down: X = x cos θ + z sin θ), in the world frame on the conveyor
surface. Equations (4.27)-(4.29), with the finger forces summed over both
drums (Q_X, Q_Z, moment T_Y about the centre):

    m Ẍ = Q_X + F_c
    m Z̈ = Q_Z - m g + N + F_leg,        F_leg = -k (Z - γ) - c Ż
    I θ̈ = T_Y + (conveyor force's moment at the lowest point A)

The conveyor pushes up at A with N ≥ 0 and drags it with F_c (Coulomb,
coefficient µ_c). Three modes, each an ODE:

* ``air``: N = F_c = 0 (the bird is held or flying);
* ``slip``: A stays on the conveyor, Z = D(θ), and F_c = -µ_c N sgn(s),
  s = V_A - v the slip of A (eq. 4.36, 4.40);
* ``stick``: A stays on the conveyor and moves with it (s ≡ 0), F_c whatever
  holds it there while |F_c| ≤ µ_c N.

Switches (detected as events by the integrator): N → 0 (lift-off), the
lowest point reaching the surface (touch-down, plastic impact), |F_c| → µ_c N
(stick to slip), s → 0 (slip to stick).

Leg model: the thesis gives c and k but no values. Default k = 30 N/m,
c = 1.5 N s/m: a lift of the mean bird by 80 mm is resisted by 2.4 N, 14% of
its weight; the sensitivity of the hold time to them is tested.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from design.physics.backend import ops
from design.physics.kinematics import lowest_point

G = 9.81
MODES = ("air", "slip", "stick")


@dataclass(frozen=True)
class Bird:
    """An ellipsoidal bird: semi-axes η (length), λ (width), γ (height) in m,
    mass (kg), pitch moment of inertia I_y (kg m²)."""

    eta: float
    lam: float
    gamma: float
    mass: float
    inertia: float
    name: str = ""

    def describe(self) -> dict:
        return {"name": self.name, "semi_axes": [self.eta, self.lam, self.gamma],
                "mass": self.mass, "inertia_y": self.inertia}


@dataclass(frozen=True)
class Legs:
    """Leg spring (N/m) and damper (N s/m) between body and conveyor (eq. 4.28)."""

    stiffness: float = 30.0
    damping: float = 1.5


@dataclass(frozen=True)
class Conveyor:
    """Belt speed v(t): ``speed`` (m/s) until the deceleration starts, then down
    at ``rate`` (m/s²) to ``final_speed``. The start is a time, or the time the
    bird's centre first passes ``start_position`` (m), whichever is given;
    neither: constant speed."""

    speed: float
    final_speed: float | None = None
    rate: float = 2.0
    start_time: float | None = None
    start_position: float | None = None

    @property
    def decelerates(self) -> bool:
        return self.final_speed is not None and (self.start_time is not None or
                                                 self.start_position is not None)

    @property
    def changes(self) -> bool:
        """Whether the belt's speed changes: it decelerates to a final speed
        other than its own."""
        return self.decelerates and self.final_speed != self.speed

    def velocity(self, t: float, start: float | None) -> tuple[float, float]:
        """Speed (m/s) and acceleration (m/s²) at t, given the start time."""
        if not self.changes or start is None:
            return self.speed, 0.0
        v, v_dot, _ = belt_motion(t, self.speed, self.final_speed, self.rate, start)
        return v, v_dot

    def describe(self) -> dict:
        return {"speed": self.speed, "final_speed": self.final_speed, "rate": self.rate,
                "start_time": self.start_time, "start_position": self.start_position}


def belt_motion(t, speed, final_speed, rate, start):
    """Belt speed v (m/s), acceleration (m/s²) and distance travelled since
    t = 0 (m) when it slows from ``speed`` at ``rate`` to ``final_speed``
    from time ``start`` on (any argument may be symbolic)."""
    xp = ops(t, speed, final_speed, rate, start)
    ramp = (speed - final_speed) / rate
    tau = xp.fmin(xp.fmax(t - start, 0.0), ramp)
    v = speed - rate * tau
    slowing = xp.if_else((t - start > 0) * (t - start < ramp), 1.0, 0.0)
    travel = speed * t - rate * tau ** 2 / 2 - (speed - final_speed) * xp.fmax(t - start - ramp, 0)
    return v, -rate * slowing, travel


@dataclass
class Loads:
    """Finger forces summed over both drums (N, N m about the centre)."""

    qx: float = 0.0
    qz: float = 0.0
    ty: float = 0.0


class BirdDynamics:
    """Accelerations and conveyor forces of the bird for each mode."""

    def __init__(self, bird: Bird, legs: Legs, friction: float):
        self.bird, self.legs, self.mu = bird, legs, float(friction)

    def support(self, theta):
        """Lowest point: (x_A ahead of the centre, D, dD/dθ, d²D/dθ²)."""
        b = self.bird
        x_a, D = lowest_point(b.eta, b.gamma, theta)
        # D² = γ² cos² θ + η² sin² θ: D D' = (η² - γ²) s c, so D' = x_A
        d1 = x_a
        d2 = ((b.eta ** 2 - b.gamma ** 2) * ops(theta).cos(2 * theta) - d1 ** 2) / D
        return x_a, D, d1, d2

    def gap(self, y: np.ndarray) -> float:
        """Height of the lowest point above the conveyor, m."""
        return float(y[1] - self.support(y[2])[1])

    def slip(self, y: np.ndarray, v: float) -> float:
        """Slip velocity of the lowest point over the belt, m/s."""
        _, D, _, _ = self.support(y[2])
        return float(y[3] - y[5] * D - v)

    def leg_force(self, y):
        return -self.legs.stiffness * (y[1] - self.bird.gamma) - self.legs.damping * y[4]

    def accelerations(self, y, loads: Loads, mode: str, v_dot, slip_sign: float = 0.0):
        """(Ẍ, Z̈, θ̈), N and F_c in ``mode`` (y, loads and v̇ numbers or CasADi
        symbols; floats N, F_c for numbers).

        On the conveyor the constraint Z = D(θ) gives Z̈ = D'' θ̇² + D' θ̈; in
        stick, additionally Ẍ - D θ̈ - D' θ̇² = v̇. Linear in the unknowns.
        """
        b = self.bird
        m, inertia = b.mass, b.inertia
        xp = ops(y, loads.qx, loads.qz, loads.ty, v_dot)
        fz = loads.qz - m * G + self.leg_force(y)
        if mode == "air":
            return xp.vector([loads.qx / m, fz / m, loads.ty / inertia]), 0.0, 0.0
        x_a, D, d1, d2 = self.support(y[2])
        th_dot = y[5]
        # unknowns u = (Ẍ, Z̈, θ̈, N, F_c); moment of (F_c, N) at A = (x_A, -D) about the
        # centre, about +Y: r_z F_x - r_x F_z = -D F_c - x_A N
        rows = [[m, 0, 0, 0, -1], [0, m, 0, -1, 0], [0, 0, inertia, x_a, D], [0, 1, -d1, 0, 0]]
        r = [loads.qx, fz, loads.ty, d2 * th_dot ** 2]
        if mode == "slip":
            rows.append([0, 0, 0, self.mu * slip_sign, 1])
            r.append(0.0)
        else:
            rows.append([1, 0, -D, 0, 0])
            r.append(v_dot + d1 * th_dot ** 2)
        u = xp.solve(xp.matrix(rows), xp.vector(r))
        return u[:3], u[3], u[4]

    def rhs(self, y: np.ndarray, loads: Loads, mode: str, v_dot: float,
            slip_sign: float = 0.0) -> np.ndarray:
        acc, _, _ = self.accelerations(y, loads, mode, v_dot, slip_sign)
        return np.concatenate([y[3:], acc])

    def land(self, y: np.ndarray) -> np.ndarray:
        """Touch-down: a plastic, frictionless impulse at A stops A's vertical
        motion; momentum and moment of momentum about A are balanced."""
        b = self.bird
        x_a, D, _, _ = self.support(y[2])
        v_n = y[4] - y[5] * x_a                     # vertical velocity of A
        impulse = -v_n / (1 / b.mass + x_a ** 2 / b.inertia)
        return ops(y).vector([y[0], D, y[2], y[3], y[4] + impulse / b.mass,
                              y[5] - x_a * impulse / b.inertia])

    def settle(self, y: np.ndarray) -> np.ndarray:
        """Project a state onto the conveyor constraint (Z = D, Ż = D' θ̇)."""
        _, D, d1, _ = self.support(y[2])
        y = y.copy()
        y[1], y[4] = D, d1 * y[5]
        return y
