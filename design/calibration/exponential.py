"""The thesis's exponential family fitted to a fitted EI(s).

EI(s) = E (A e^(a s) + B e^(b s) + C) (thesis eq. 2.33) with the rates a, b
fixed (the thesis's by default) is linear in (A, B, C): weighted least
squares against the knot profile where the data determine it, each knot
weighted by its band (1 / standard deviation of EI), with EI ≥ 10 % of the
fitted profile's smallest value along the whole finger so the family cannot
dip towards zero between knots. A small convex QP (cvxpy, Clarabel).

This is a projection of the measured profile onto the family, not a second
fit to the measurements: the run reports how well the projected model
predicts them.
"""

from __future__ import annotations

import cvxpy as cp
import numpy as np

from design.calibration.convex import SOLVER
from design.physics.stiffness import ExponentialI


def project(knots: np.ndarray, ei: np.ndarray, ei_sd: np.ndarray, weight_mask: np.ndarray,
            length: float, E: float, rates: tuple[float, float]) -> ExponentialI:
    """ExponentialI(E, A, B, C, a, b) closest to ``ei`` (N m²) at the masked
    knots (m), in units of its standard deviation ``ei_sd``."""
    a, b = rates
    s = knots[weight_mask]
    basis = E * np.stack([np.exp(a * s), np.exp(b * s), np.ones_like(s)], axis=1)
    scale = float(np.median(ei[weight_mask])) / E            # m^4: keeps the QP O(1)
    theta = cp.Variable(3)
    w = 1.0 / np.maximum(ei_sd[weight_mask], 1e-12 * ei[weight_mask])
    objective = cp.sum_squares(cp.multiply(w, basis @ theta * scale - ei[weight_mask]))
    grid = np.linspace(0.0, length, 201)
    full = E * np.stack([np.exp(a * grid), np.exp(b * grid), np.ones_like(grid)], axis=1)
    floor = 0.1 * float(np.min(ei))
    cp.Problem(cp.Minimize(objective), [full @ theta * scale >= floor]).solve(solver=SOLVER)
    A, B, C = np.asarray(theta.value) * scale
    return ExponentialI(E, float(A), float(B), float(C), a, b)
