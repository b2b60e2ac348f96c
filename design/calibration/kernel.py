"""The small-deflection kernel: measured deflections and slopes linear in c(s).

For a cantilever clamped at s = 0 with compliance c(s) = 1/EI(s) (1/(N m²)),
a transverse load P = F sin α (N) at arc length a bends it, in linear beam
theory (thesis eq. 2.4; the axial part of the load is ignored), to

    w(x) = P ∫_0^min(x, a) (a - s)(x - s) c(s) ds       (deflection, m)
    ψ(x) = P ∫_0^min(x, a) (a - s) c(s) ds              (slope, rad)

(M = P (a - s) integrated twice; past the load the finger is straight). With
c piecewise linear on knots s_0 = 0 < ... < s_n = length (hat functions
φ_j), every measurement is a row of a matrix acting on the knot values:
y = K c. The along-the-finger position x does not change to first order, so
x measurements have no row (the elastica fit uses them).
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from design.calibration.data import FingerData, Observation
from design.physics.stiffness import Stiffness

#: Gauss-Legendre points on [0, 1] (3 points: exact for the cubic integrands here)
_GX, _GW = np.polynomial.legendre.leggauss(3)
_GX, _GW = (_GX + 1) / 2, _GW / 2


def hat_values(knots: np.ndarray, s: np.ndarray) -> np.ndarray:
    """φ_j(s) for every knot j: the piecewise-linear interpolation matrix
    (len(s) x len(knots)); s outside the knots is clamped to them."""
    s = np.clip(np.asarray(s, dtype=float), knots[0], knots[-1])
    out = np.zeros((s.size, knots.size))
    k = np.clip(np.searchsorted(knots, s, side="right") - 1, 0, knots.size - 2)
    t = (s - knots[k]) / (knots[k + 1] - knots[k])
    out[np.arange(s.size), k] = 1 - t
    out[np.arange(s.size), k + 1] = t
    return out


def kernel_row(knots: np.ndarray, transverse: float, at: float, point: float,
               quantity: str) -> np.ndarray:
    """The row K_j = P ∫_0^m w(s) φ_j(s) ds of one measurement (m = min(x, a),
    w = (a - s)(x - s) for a deflection, (a - s) for a slope)."""
    end = min(point, at)
    row = np.zeros(knots.size)
    for k in range(knots.size - 1):
        lo, hi = knots[k], min(knots[k + 1], end)
        if hi <= lo:
            break
        s = lo + (hi - lo) * _GX
        weight = (at - s) * ((point - s) if quantity == "y" else 1.0) * _GW * (hi - lo)
        t = (s - knots[k]) / (knots[k + 1] - knots[k])
        row[k] += weight @ (1 - t)
        row[k + 1] += weight @ t
    return transverse * row


def kernel(knots: np.ndarray, data: FingerData) -> tuple[np.ndarray, list[int]]:
    """The matrix K (rows: the deflection and slope observations, columns:
    knots) and the indices of those observations in ``data.observations``."""
    rows, used = [], []
    for i, o in enumerate(data.observations):
        if o.quantity == "x":
            continue
        load = data.loads[o.case]
        rows.append(kernel_row(knots, load.components[1], load.at, o.s, o.quantity))
        used.append(i)
    return np.array(rows).reshape(len(used), knots.size), used


def linear_prediction(knots: np.ndarray, c: np.ndarray, data: FingerData,
                      observation: Observation) -> float:
    """The small-deflection value of one observation (x: the point's s)."""
    load = data.loads[observation.case]
    if observation.quantity == "x":
        return observation.s
    return float(kernel_row(knots, load.components[1], load.at, observation.s,
                            observation.quantity) @ c)


@dataclass(frozen=True, eq=False)
class KnotCompliance(Stiffness):
    """EI(s) = 1 / c(s), c piecewise linear through ``c`` (1/(N m²)) at
    ``knots`` (m, increasing from 0). Its CasADi parameters are the knot
    compliances, so a collocated elastica can have them as unknowns.
    EI is continuous with kinks at the knots (C0)."""

    knots: tuple[float, ...]
    c: tuple[float, ...]
    smoothness = 0

    def _c(self, s):
        return np.interp(np.asarray(s, dtype=float), self.knots, self.c)

    def ei(self, s):
        return 1.0 / self._c(s)

    def dei(self, s):
        s = np.asarray(s, dtype=float)
        k = np.clip(np.searchsorted(self.knots, s, side="right") - 1, 0, len(self.knots) - 2)
        kn, c = np.asarray(self.knots), np.asarray(self.c)
        slope = (c[k + 1] - c[k]) / (kn[k + 1] - kn[k])
        return -slope / self._c(s) ** 2

    @property
    def params(self):
        return np.asarray(self.c, dtype=float)

    def ei_casadi(self, s, p):
        return 1.0 / compliance_casadi(np.asarray(self.knots), s, p)

    def symbolic_key(self):
        return (type(self).__name__, self.knots)

    def scaled(self, factor):
        return KnotCompliance(self.knots, tuple(np.asarray(self.c) / factor))

    def describe(self):
        return {"type": "knot-compliance", "s": list(self.knots),
                "EI": list(1.0 / np.asarray(self.c))}


def compliance_casadi(knots: np.ndarray, s, p):
    """c(s) = Σ_j p_j φ_j(s), piecewise linear through p at ``knots`` (clamped
    outside them), as a CasADi expression. The hats are written as
    φ_j = max(0, min((s - s_(j-1)) / h_(j-1), (s_(j+1) - s) / h_j)) so that,
    at a numeric s, all but two are exact zeros: the collocation equations
    then depend on two knots each and the refinement's Hessian stays sparse."""
    h = ca.DM(np.diff(knots))
    rise = ca.vertcat(1, (s - ca.DM(knots[:-1])) / h)
    fall = ca.vertcat((ca.DM(knots[1:]) - s) / h, 1)
    return ca.sum1(p * ca.fmax(0, ca.fmin(rise, fall)))
