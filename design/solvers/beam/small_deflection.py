"""Small-deflection (linear) beam theory, thesis eqs. (2.4)-(2.5).

EI(x) y'' = F sin α (L - x), y(0) = y'(0) = 0, x = s (no shortening); the
axial component of the force is ignored. Uniform EI gives eq. (2.5),

    y = F sin α L^3 / (2 EI) (x/L)^2 (1 - x/(3L)),

any other profile is integrated by cumulative Simpson quadrature on
``nodes`` intervals.

Error estimate. The error that matters is the model's, not the quadrature's:
it is estimated from two Picard steps of the elastica from the linear shape
(:func:`picard`, :func:`picard_error`): within 2% of the true load-point
error for F L^2/EI ≤ 0.5, and "large" where the linear model is poor.
"""

from __future__ import annotations

import numpy as np
from scipy.integrate import cumulative_simpson

from design.physics.beam import BeamSolution, PointLoad, normalise_angle, straight_solution
from design.solvers.beam.base import BeamMethod


def _cumint(f: np.ndarray, s: np.ndarray) -> np.ndarray:
    return cumulative_simpson(f, x=s, initial=0.0)


def picard(s: np.ndarray, psi: np.ndarray, load: PointLoad, stiffness, steps: int
           ) -> list[tuple[np.ndarray, ...]]:
    """Picard steps of the elastica from a slope ψ(s) on the grid ``s``.

    Each step takes the geometry of the current ψ, recomputes the moment of
    the full force about every point, and integrates ψ = ∫M/EI again. The
    iteration contracts like (F L^2/EI) per step for moderate loads.

    Returns the iterates [(x, y, ψ, M), ...], the first one for the input ψ.
    """
    fx, fy = load.components
    out = []
    for i in range(steps + 1):
        x, y = _cumint(np.cos(psi), s), _cumint(np.sin(psi), s)
        moment = (x[-1] - x) * fy - (y[-1] - y) * fx
        out.append((x, y, psi, moment))
        if i < steps:
            psi = _cumint(moment / stiffness.ei(s), s)
    return out


def picard_error(tips: list[tuple[float, float]]) -> float:
    """Distance from the first of three successive load points to the limit.

    The first change is first-order accurate in the neglected nonlinearity;
    a compressive axial force amplifies the following ones (P-δ) and a
    tensile one makes them alternate; the signed ratio r of the second change
    to the first captures both: e1 / (1 - r), the geometric series' sum (as
    Aitken's), or e1 + e2 / (1 - 0.9) when the steps do not contract.
    """
    v1 = np.subtract(tips[1], tips[0])
    v2 = np.subtract(tips[2], tips[1])
    e1 = float(np.hypot(*v1))
    r = float(v2 @ v1) / e1 ** 2 if e1 > 0 else 0.0     # < 0: the steps alternate (tension)
    return e1 / (1 - r) if -1 < r < 0.9 else e1 + float(np.hypot(*v2)) / 0.1


class SmallDeflection(BeamMethod):
    """Linear beam theory; ``nodes`` = quadrature intervals along [0, L]."""

    name = "small-deflection"
    order = None
    default_nodes = 400

    def solve(self, loads):
        return [self._solve_one(ld) for ld in loads]

    def _solve_one(self, load: PointLoad) -> BeamSolution:
        if load.force == 0.0:
            return straight_solution(load, self.name, self.nodes + 1, message="no load")
        stiff = self.finger.stiffness
        L = load.at
        s = np.linspace(0.0, L, self.nodes + 1)
        fx, fy = load.components
        if stiff.uniform:
            ei = float(stiff.ei(0.0))
            psi = fy / ei * (L * s - s ** 2 / 2)
            y = fy * L ** 3 / (2 * ei) * (s / L) ** 2 * (1 - s / (3 * L))
        else:
            psi = _cumint(fy * (L - s) / stiff.ei(s), s)
            y = _cumint(psi, s)
        x = s.copy()
        moment = fy * (L - s)
        steps = picard(s, psi, load, stiff, 2)
        err = picard_error([(x[-1], y[-1])] + [(it[0][-1], it[1][-1]) for it in steps[1:]])
        axial = abs(np.sin(normalise_angle(load.alpha))) < 1e-12
        return BeamSolution(load, self.name, s, x, y, psi, moment, error_estimate=err,
                            converged=True, branch="straight" if axial else "primary",
                            message="linear theory: axial load ignored" if axial else "")
