"""Belt speed profiles from an encoder log (time, speed).

Two fits of the same samples:

* the model-free one: a non-increasing piecewise-linear v(t) on uniform knots
  over the log, by least squares (monotone least squares, a convex QP:
  cvxpy with Clarabel, as in :mod:`design.calibration.convex`);
* the toolkit's conveyor model (:class:`design.physics.bird.Conveyor`):
  v0 until t_s, down at a constant rate to v1 at t_e, then v1. For fixed
  (t_s, t_e) the model is linear in (v0, v1), so every pair of breakpoints
  on a grid is solved exactly by linear least squares, and the best pair is
  polished with all four parameters free (scipy's trust-region least
  squares); standard errors from its Jacobian and the residuals.

The second is what a conveyor file can hold; the first checks that shape:
if the conveyor model's residuals are much larger than the monotone fit's,
the belt does not slow as one constant-rate ramp.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import cvxpy as cp
import numpy as np
from scipy.optimize import least_squares

from design.calibration.convex import SOLVER
from design.calibration.kernel import hat_values

#: candidate breakpoints per axis of the grid search
GRID = 120
#: a speed drop smaller than this many standard errors is no deceleration
SIGNIFICANT = 3.0


@dataclass
class MonotoneFit:
    """Knot times (s) and speeds (m/s) of the non-increasing piecewise-linear fit."""

    knots: np.ndarray
    speeds: np.ndarray
    predictions: np.ndarray
    rms: float
    solve_time_s: float
    status: str


@dataclass
class RampFit:
    """Constant, ramp, constant: v0 (m/s) until t_s (s), v1 from t_e on; the
    standard errors (same units) and the residuals' RMS (m/s)."""

    v0: float
    v1: float
    t_start: float
    t_end: float
    se: dict
    predictions: np.ndarray
    rms: float
    decelerates: bool
    solve_time_s: float

    @property
    def rate(self) -> float:
        """Deceleration, m/s² (0 when the belt does not slow)."""
        return (self.v0 - self.v1) / (self.t_end - self.t_start) if self.decelerates else 0.0


def monotone_fit(t: np.ndarray, v: np.ndarray, knots: int) -> MonotoneFit:
    """Least-squares non-increasing piecewise-linear speed on ``knots``
    uniform knots over the log (cvxpy, Clarabel)."""
    tk = np.linspace(t[0], t[-1], knots)
    Phi = hat_values(tk, t)
    theta = cp.Variable(knots)
    problem = cp.Problem(cp.Minimize(cp.sum_squares(Phi @ theta - v)), [cp.diff(theta) <= 0])
    t0 = time.perf_counter()
    problem.solve(solver=SOLVER)
    elapsed = time.perf_counter() - t0
    speeds = np.asarray(theta.value)
    pred = Phi @ speeds
    return MonotoneFit(tk, speeds, pred, float(np.sqrt(np.mean((pred - v) ** 2))), elapsed,
                       problem.status)


def ramp(t: np.ndarray, v0: float, v1: float, ts: float, te: float) -> np.ndarray:
    """v0 before ts, v1 after te, linear between (m/s)."""
    g = np.clip((t - ts) / max(te - ts, 1e-12), 0.0, 1.0)
    return v0 + (v1 - v0) * g


def ramp_fit(t: np.ndarray, v: np.ndarray) -> RampFit:
    """The conveyor model's four parameters by least squares (see the module docstring)."""
    t0 = time.perf_counter()
    cand = np.linspace(t[0], t[-1], GRID)
    best = (np.inf, None)
    for i, ts in enumerate(cand[:-1]):
        te = cand[i + 1:]
        g = np.clip((t[None, :] - ts) / (te[:, None] - ts), 0.0, 1.0)   # (pairs, samples)
        # v ≈ v0 (1 - g) + v1 g: 2x2 normal equations for every te at once
        a11, a12, a22 = ((1 - g) ** 2).sum(1), ((1 - g) * g).sum(1), (g ** 2).sum(1)
        b1, b2 = ((1 - g) * v).sum(1), (g * v).sum(1)
        det = a11 * a22 - a12 ** 2
        ok = det > 1e-12 * np.maximum(a11 * a22, 1e-300)
        v0 = np.where(ok, (a22 * b1 - a12 * b2) / np.where(ok, det, 1), v.mean())
        v1 = np.where(ok, (a11 * b2 - a12 * b1) / np.where(ok, det, 1), v.mean())
        sse = (((v0[:, None] * (1 - g) + v1[:, None] * g) - v[None, :]) ** 2).sum(1)
        j = int(np.argmin(sse))
        if sse[j] < best[0]:
            best = (sse[j], (v0[j], v1[j], ts, te[j]))
    x0 = np.array(best[1])
    span = t[-1] - t[0]
    res = least_squares(lambda p: ramp(t, *p) - v, x0, method="trf",
                        bounds=([0, 0, t[0] - span, t[0]], [np.inf, np.inf, t[-1], t[-1] + span]),
                        x_scale=[abs(x0[0]) + 1e-3, abs(x0[1]) + 1e-3, span, span])
    v0, v1, ts, te = res.x
    pred = ramp(t, *res.x)
    dof = max(t.size - 4, 1)
    s2 = float(res.fun @ res.fun) / dof
    cov = s2 * np.linalg.pinv(res.jac.T @ res.jac)
    se = dict(zip(("v0", "v1", "t_start", "t_end"), np.sqrt(np.clip(np.diag(cov), 0, None))))
    # the rate (v0 - v1) / (te - ts) by the delta method
    dt = te - ts
    grad = np.array([1 / dt, -1 / dt, (v0 - v1) / dt ** 2, -(v0 - v1) / dt ** 2])
    se["rate"] = float(np.sqrt(max(grad @ cov @ grad, 0.0)))
    drop_se = float(np.sqrt(max(cov[0, 0] + cov[1, 1] - 2 * cov[0, 1], 0.0)))
    decel = bool(v0 - v1 > SIGNIFICANT * drop_se and te > ts)
    if not decel:                       # one speed: the mean
        v0 = v1 = float(v.mean())
        pred = np.full_like(v, v0)
    elapsed = time.perf_counter() - t0
    return RampFit(float(v0), float(v1), float(ts), float(te), se, pred,
                   float(np.sqrt(np.mean((pred - v) ** 2))), decel, elapsed)
