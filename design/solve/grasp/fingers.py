"""Finger forces on the bird in 3-D, both drums (thesis §4.3; MODEL.md §4).

For every finger of the right drum at time t and bird pose (X, Z, θ): the
finger's frame, the ellipse in which its bending plane cuts the bird, the
2-D contact solved in that plane (continued from the finger's previous
state), and the force mapped back to the world. The left drum's finger is
the mirror image: same force magnitudes, Y components opposite, so the
symmetric grasp sees twice the right drum's X and Z forces and moment.

Model only what can touch: :func:`reach_windows` finds, from the undeformed
finger loci (eq. 5.1), the time windows in which a finger can reach the bird
at all; outside them no contact problem is built or solved.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from design.physics.bird import Bird, Loads
from design.physics.contact import ContactSolution
from design.physics.ellipse import Ellipse
from design.physics.grasper import Grasper
from design.physics.kinematics import Ellipsoid
from design.solve.contact import RobustContact

#: finite-difference step (s) for the rates the friction direction needs
RATE_STEP = 1e-6
#: a finger's friction reverses only when it slides the other way faster than
#: this (m/s): flipping it at every sign change of the sliding speed, decided
#: at accepted steps, chatters (measured: 50-80 N force jumps every 1-5 ms)
REVERSAL_SPEED = 0.02


@dataclass
class FingerState:
    """One finger's contact at one instant (right drum), world frame."""

    force: np.ndarray = field(default_factory=lambda: np.zeros(3))   # on the bird, N
    point: np.ndarray | None = None                                  # world, m
    body_point: np.ndarray | None = None                             # bird frame, m
    solution: ContactSolution | None = None

    @property
    def magnitude(self) -> float:
        return float(np.linalg.norm(self.force))


def reach_windows(grasper: Grasper, bird: Bird, speed: float, centre_path, t_end: float,
                  margin: float = 0.15, dt: float = 1e-3) -> list[list[tuple[float, float]]]:
    """Per finger, the time windows (s) in which its straight finger can touch
    the bird, padded by one sample.

    Conservative: the bird's centre is anywhere within ``margin`` (m) of
    ``centre_path(t)`` = (X, Z) along X and between the conveyor and ``margin``
    above the path in Z, and any orientation; a finger can touch only if its
    undeformed segment comes within the largest semi-axis of that region.
    Contact needs the straight finger to enter the bird, so outside these
    windows the force is zero.
    """
    drum = grasper.drum(speed)
    times = np.arange(0.0, t_end + dt, dt)
    reach = max(bird.eta, bird.lam, bird.gamma)
    out = []
    for gf in grasper.fingers:
        near = np.zeros(times.size, dtype=bool)
        for k, t in enumerate(times):
            base, R = drum.frame(gf.mount, t)
            tip = base + gf.finger.length * R[:, 0]
            x_c, z_c = centre_path(t)
            near[k] = _segment_box_distance(base, tip, (x_c - margin, x_c + margin),
                                            (0.0, 0.0), (0.0, z_c + margin)) <= reach
        windows = []
        k = 0
        while k < near.size:
            if near[k]:
                j = k
                while j + 1 < near.size and near[j + 1]:
                    j += 1
                windows.append((max(0.0, times[k] - dt), times[j] + dt))
                k = j + 1
            else:
                k += 1
        out.append(windows)
    return out


def _segment_box_distance(a, b, xr, yr, zr, samples: int = 24) -> float:
    """Smallest distance (m) from a segment to an axis-aligned box (sampled)."""
    s = np.linspace(0.0, 1.0, samples)[:, None]
    p = a[None, :] + s * (b - a)[None, :]
    lo = np.array([xr[0], yr[0], zr[0]])
    hi = np.array([xr[1], yr[1], zr[1]])
    d = np.maximum(np.maximum(lo - p, 0.0), p - hi)
    return float(np.min(np.linalg.norm(d, axis=1)))


class FingerForces:
    """All fingers' forces on the bird, continued in time finger by finger.

    ``evaluate(t, y, commit)`` returns the summed loads and each finger's
    state. Trial evaluations (``commit`` false) keep each contact's friction
    ratio from the last committed state; committed ones (accepted integrator
    steps) also decide it from the sliding velocity and become the states
    later evaluations continue from.
    """

    def __init__(self, grasper: Grasper, bird: Bird, drum_speed: float, friction: float,
                 windows: list[list[tuple[float, float]]] | None = None,
                 intervals: int = 8, degree: int = 4, reversal_speed: float = REVERSAL_SPEED):
        self.grasper, self.bird = grasper, bird
        self.drum = grasper.drum(drum_speed)
        self.solvers = [RobustContact(gf.finger, friction, intervals=intervals, degree=degree,
                                      reversal_speed=reversal_speed)
                        for gf in grasper.fingers]
        self.windows = windows
        self.states: list = [None] * len(grasper.fingers)    # at the last accepted step
        self.trials: list = [None] * len(grasper.fingers)    # at the latest evaluation
        self.solves = 0            # contact problems solved
        self.skipped = 0           # finger evaluations the reach windows saved
        self._memo: dict = {}      # trial evaluations since the last commit

    def active(self, i: int, t: float) -> bool:
        if self.windows is None:
            return True
        return any(a <= t <= b for a, b in self.windows[i])

    def ellipsoid(self, y: np.ndarray) -> Ellipsoid:
        b = self.bird
        return Ellipsoid(b.eta, b.lam, b.gamma, (y[0], 0.0, y[1]), y[2])

    def evaluate(self, t: float, y: np.ndarray, commit: bool = False
                 ) -> tuple[Loads, list[FingerState]]:
        key = (t, y.tobytes())
        if not commit and key in self._memo:
            return self._memo[key]
        out = self._evaluate(t, y, commit)
        if commit:
            self._memo.clear()
        elif len(self._memo) > 16:
            self._memo.pop(next(iter(self._memo)))
        self._memo[key] = out
        return out

    def _evaluate(self, t: float, y: np.ndarray, commit: bool) -> tuple[Loads, list[FingerState]]:
        body = self.ellipsoid(y)
        loads, states = Loads(), []
        centre = np.array([y[0], 0.0, y[1]])
        for i, gf in enumerate(self.grasper.fingers):
            if not self.active(i, t):
                self.skipped += 1
                self.trials[i] = None
                if commit:
                    self.states[i] = None
                states.append(FingerState())
                continue
            base, R = self.drum.frame(gf.mount, t)
            cut = body.cut(base, R)
            if cut is None:
                self.trials[i] = None
                if commit:
                    self.states[i] = None
                states.append(FingerState())
                continue
            kin = self._kinematics(i, t, y, cut)
            self.solves += 1
            # continue from the latest solution, trial or committed: the nearest
            # in time (trials keep the committed friction ratio)
            start = self.states[i] if commit else self.trials[i]
            sol, cont = self.solvers[i].solve_frame(cut, "auto", kin, start,
                                                    settle=commit, detail=commit)
            self.trials[i] = cont
            if commit:
                self.states[i] = cont
            if not sol.contact:
                states.append(FingerState(solution=sol))
                continue
            f_w = R[:, :2] @ sol.force_on_object_finger_frame
            p_w = base + R[:, :2] @ np.asarray(sol.point)
            r = p_w - centre
            loads.qx += 2 * f_w[0]
            loads.qz += 2 * f_w[2]
            loads.ty += 2 * (r[2] * f_w[0] - r[0] * f_w[2])
            states.append(FingerState(f_w, p_w, body.rotation.T @ r, sol))
        return loads, states

    def _kinematics(self, i: int, t: float, y: np.ndarray, cut: Ellipse):
        """Rates of the cut ellipse and the bird's surface velocity relative to
        finger i's frame, by a forward difference over RATE_STEP."""
        gf = self.grasper.fingers[i]
        dt = RATE_STEP
        y2 = y.copy()
        y2[:3] += dt * y[3:]
        base, R = self.drum.frame(gf.mount, t)
        base2, R2 = self.drum.frame(gf.mount, t + dt)
        body, body2 = self.ellipsoid(y), self.ellipsoid(y2)

        def kin(p_f: np.ndarray):
            cut2 = body2.cut(base2, R2)
            if cut2 is None:
                q_dot = np.zeros(5)
            else:
                a2, b2, th2 = cut2.a, cut2.b, cut2.theta
                # the same ellipse may come back with its axes swapped or θ + π
                if abs(a2 - cut.a) + abs(b2 - cut.b) > abs(b2 - cut.a) + abs(a2 - cut.b):
                    a2, b2, th2 = b2, a2, th2 + np.pi / 2
                d_th = (th2 - cut.theta + np.pi / 2) % np.pi - np.pi / 2
                q_dot = np.array([cut2.center[0] - cut.center[0], cut2.center[1] - cut.center[1],
                                  d_th, a2 - cut.a, b2 - cut.b]) / dt
            p_w = base + R[:, :2] @ p_f
            p_b = body.rotation.T @ (p_w - np.array(body.center))
            p_w2 = np.array(body2.center) + body2.rotation @ p_b
            p_f2 = R2.T @ (p_w2 - base2)
            return q_dot, (p_f2[:2] - p_f) / dt

        return kin

    @staticmethod
    def left(state: FingerState) -> tuple[np.ndarray, np.ndarray | None]:
        """The mirror finger's force and point on the left drum."""
        m = np.array([1.0, -1.0, 1.0])
        return state.force * m, None if state.point is None else state.point * m

