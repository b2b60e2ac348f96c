"""Small-deflection (linear) beam theory, thesis eqs. (2.4)-(2.5).

EI(x) y'' = F sin α (L - x), y(0) = y'(0) = 0, x = s (no shortening); the
axial component of the force is ignored. Uniform EI gives eq. (2.5),

    y = F sin α L^3 / (2 EI) (x/L)^2 (1 - x/(3L)),

any other profile is integrated by cumulative Simpson quadrature on
``nodes`` intervals.

Error estimate. The error that matters is the model's, not the quadrature's:
it is estimated by one Picard step of the elastica from the linear shape
(the moment recomputed with the deflected geometry and the full force, then
ψ, x, y integrated again). The estimate is the load-point distance between
that corrected shape and the linear one; it is first-order accurate in the
neglected nonlinearity, so it is reliable where the linear model is useful
and says "large" where it is not.
"""

from __future__ import annotations

import numpy as np
from scipy.integrate import cumulative_simpson

from design.physics.beam import BeamSolution, PointLoad, normalise_angle, straight_solution
from design.solve.beam.base import BeamMethod


def _cumint(f: np.ndarray, s: np.ndarray) -> np.ndarray:
    return cumulative_simpson(f, x=s, initial=0.0)


def _picard_estimate(s, psi, x_tip, y_tip, load, stiff) -> float:
    """Distance from the linear load point to the elastica's, by Picard steps.

    Each step recomputes the moment with the deflected geometry and the full
    force, then ψ, x and y. The first step's change is first-order accurate
    in the neglected nonlinearity; a compressive axial force amplifies it
    (P-δ), which the ratio r of the second change to the first captures:
    the estimate is e1 / (1 - r) (Aitken), or e1 + e2 / (1 - 0.9) when the
    steps do not contract.
    """
    fx, fy = load.components
    tips = [(x_tip, y_tip)]
    for _ in range(2):
        xd, yd = _cumint(np.cos(psi), s), _cumint(np.sin(psi), s)
        moment = (xd[-1] - xd) * fy - (yd[-1] - yd) * fx
        psi = _cumint(moment / stiff.ei(s), s)
        tips.append((_cumint(np.cos(psi), s)[-1], _cumint(np.sin(psi), s)[-1]))
    e1 = float(np.hypot(tips[1][0] - tips[0][0], tips[1][1] - tips[0][1]))
    e2 = float(np.hypot(tips[2][0] - tips[1][0], tips[2][1] - tips[1][1]))
    r = e2 / e1 if e1 > 0 else 0.0
    return e1 / (1 - r) if r < 0.9 else e1 + e2 / 0.1


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
        err = _picard_estimate(s, psi, x[-1], y[-1], load, stiff)
        axial = abs(np.sin(normalise_angle(load.alpha))) < 1e-12
        return BeamSolution(load, self.name, s, x, y, psi, moment, error_estimate=err,
                            converged=True, branch="straight" if axial else "primary",
                            message="linear theory: axial load ignored" if axial else "")
