"""Finite differences with Newton: the thesis's scheme (§2.2.2, eqs. 2.19-2.32).

Unknowns w_i = α1(u_i) = ψ + α at u_i = i h, h = 1/(N+1), i = 1..N, for

    α1'' = f(u, α1, α1') = -(L EI'/EI) α1' - (F L^2 / EI) sin α1      (2.15)
    w_0 = α,   w_{N+1} = (4 w_N - w_{N-1}) / 3   (α1'(1) = 0, eq. 2.26)

with central differences (second order). The Jacobian is tridiagonal
(eqs. 2.29-2.30); Newton steps are solved in O(N) with a banded solver and
damped by a backtracking line search on the residual
(:func:`design.solvers.newton.damped_newton`), seeded by the
Frisch-Fay shape of the compliance-equivalent beam. That is what keeps it
usable at any N: the thesis's undamped Newton from a crude guess is what
diverged as the mesh was refined.
"""

from __future__ import annotations

import numpy as np
from scipy.linalg import solve_banded

from design.physics.beam import BeamSolution, PointLoad, classify_branch
from design.solvers.beam.base import IterativeMethod, resample
from design.solvers.newton import damped_newton


class FiniteDifference(IterativeMethod):
    """Thesis FDM; ``nodes`` = N interior points (h = L/(N+1))."""

    name = "fdm"
    order = 2
    default_nodes = 399
    max_iter = 60

    def _discrete(self, load: PointLoad, guess: BeamSolution, coarse: bool) -> BeamSolution:
        n = max((self.nodes + 1) // 2 - 1, 2) if coarse else self.nodes
        return self._solve_n(load, guess, n)

    def _resolution(self, sol: BeamSolution) -> float:
        return sol.extras["N"] + 1

    def _solve_n(self, load: PointLoad, guess: BeamSolution, n: int) -> BeamSolution:
        L, alpha, force = load.at, load.alpha, load.force
        h = 1.0 / (n + 1)
        u = np.arange(n + 2) * h
        ei = self.finger.stiffness.ei(u * L)
        c = L * self.finger.stiffness.dei(u * L) / ei      # coefficient of α1'
        q = force * L ** 2 / ei                             # coefficient of sin α1
        ci, qi = c[1:-1], q[1:-1]

        def full(w):
            return np.concatenate([[alpha], w, [(4 * w[-1] - w[-2]) / 3]])

        def residual(w):
            wf = full(w)
            d1 = (wf[2:] - wf[:-2]) / (2 * h)
            g = wf[:-2] - 2 * wf[1:-1] + wf[2:] + h ** 2 * (ci * d1 + qi * np.sin(w))
            # banded Jacobian: rows (upper, diagonal, lower)
            ab = np.zeros((3, n))
            ab[0, 1:] = 1 + h * ci[:-1] / 2
            ab[1, :] = -2 + h ** 2 * qi * np.cos(w)
            ab[2, :-1] = 1 - h * ci[1:] / 2
            # last row, after eliminating w_{N+1}: G_N = w_{N-1} - 2 w_N + w_{N+1} + h^2 (...)
            # with w_{N+1} = (4 w_N - w_{N-1})/3 and α1' = 2 (w_N - w_{N-1}) / (3h)
            ab[1, -1] = -2 / 3 + 2 * h * ci[-1] / 3 + h ** 2 * qi[-1] * np.cos(w[-1])
            ab[2, -2] = 2 / 3 - 2 * h * ci[-1] / 3
            return g, ab

        psi_g, _ = resample(guess, u[1:-1])
        res = damped_newton(residual, psi_g + alpha, self.tolerance, self.max_iter,
                            solve=lambda ab, b: solve_banded((1, 1), ab, b))
        w = res.x
        wf = full(w)
        psi = wf - alpha
        dpsi = np.gradient(wf, h, edge_order=2) / L
        dpsi[-1] = 0.0
        # trapezoid, consistent with the scheme's second order
        cx, sy = np.cos(psi), np.sin(psi)
        x = L * np.concatenate([[0.0], np.cumsum((cx[1:] + cx[:-1]) * h / 2)])
        y = L * np.concatenate([[0.0], np.cumsum((sy[1:] + sy[:-1]) * h / 2)])
        return BeamSolution(load, self.name, u * L, x, y, psi, ei * dpsi,
                            error_estimate=np.inf, converged=res.converged,
                            branch=classify_branch(alpha, psi), iterations=res.iterations,
                            message=res.message, extras={"N": n})
