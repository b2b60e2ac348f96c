"""Shooting for the elastica BVP, any EI(s) (thesis §2.2.1, made robust).

Non-dimensional form on u = s/L in [0, 1], with a reference rigidity EI_r
(the compliance-equivalent uniform EI):

    ψ' = μ EI_r / EI(uL),   μ' = -κ sin(ψ + α),   κ = F L^2 / EI_r,   μ = M L / EI_r
    ψ(0) = 0,  μ(1) = 0

The thesis shoots from the base with a secant on the unknown initial slope.
Here the unknown initial moment is found by Newton with exact derivatives of
the discrete map (RK4 on the variational equations). A single shot loses all
precision once the linearised growth e^(kL) is large (near-axial and heavy
loads), so the span is cut into segments of length ≤ 2/k_max integrated in
parallel (multiple shooting); continuity at the cuts joins the Newton system.
Fixed-step classical RK4: order 4 in the number of steps ``nodes``.
"""

from __future__ import annotations

import math

import numpy as np

from design.physics.beam import BeamSolution, PointLoad, classify_branch
from design.solvers.beam.base import IterativeMethod, resample
from design.solvers.newton import damped_newton


class Shooting(IterativeMethod):
    """Multiple shooting with RK4; ``nodes`` = total RK4 steps over [0, L]."""

    name = "shooting"
    order = 4
    default_nodes = 256
    max_iter = 50

    def _discrete(self, load: PointLoad, guess: BeamSolution, coarse: bool) -> BeamSolution:
        return self._solve_steps(load, guess, max(self.nodes // 2, 2) if coarse else self.nodes)

    def _resolution(self, sol: BeamSolution) -> float:
        return sol.extras["steps"]

    def _solve_steps(self, load: PointLoad, guess: BeamSolution, steps: int) -> BeamSolution:
        L, alpha = load.at, load.alpha
        stiff = self.finger.stiffness
        ei_ref = stiff.compliance_equivalent(L)
        kappa = load.force * L ** 2 / ei_ref
        ei_min = float(np.min(stiff.ei(np.linspace(0.0, L, 65))))
        k_max_L = np.sqrt(load.force / ei_min) * L
        nseg = max(1, int(np.ceil(k_max_L / 2.0)))
        per = max(1, int(np.ceil(steps / nseg)))
        h = 1.0 / (nseg * per)
        # e(u) = EI_r / EI(uL) at every step's start, middle and end, per segment
        grid = np.arange(2 * nseg * per + 1) * (h / 2)
        e_all = (ei_ref / stiff.ei(grid * L)).tolist()

        def rates(y: tuple, e: float) -> tuple:
            """(ψ, μ, Φ00, Φ01, Φ10, Φ11)': the ODE and its sensitivity Φ' = J Φ,
            J = [[0, e], [-κ cos(ψ + α), 0]]."""
            psi, mu, p00, p01, p10, p11 = y
            c = -kappa * math.cos(psi + alpha)
            return mu * e, -kappa * math.sin(psi + alpha), e * p10, e * p11, c * p00, c * p01

        def plus(y: tuple, a: float, k: tuple) -> tuple:
            return tuple([yi + a * ki for yi, ki in zip(y, k)])

        def segment(psi0: float, mu0: float, j: int, path: list | None) -> tuple:
            """RK4 over segment j from (ψ, μ) = (psi0, mu0), Φ from the identity;
            the states at each step appended to ``path``."""
            y = (psi0, mu0, 1.0, 0.0, 0.0, 1.0)
            for i in range(2 * j * per, 2 * (j + 1) * per, 2):
                e0, e1, e2 = e_all[i], e_all[i + 1], e_all[i + 2]
                k1 = rates(y, e0)
                k2 = rates(plus(y, 0.5 * h, k1), e1)
                k3 = rates(plus(y, 0.5 * h, k2), e1)
                k4 = rates(plus(y, h, k3), e2)
                y = tuple([a + h / 6 * (q1 + 2 * q2 + 2 * q3 + q4)
                           for a, q1, q2, q3, q4 in zip(y, k1, k2, k3, k4)])
                if path is not None:
                    path.append(y[:2])
            return y

        def shoot(psi0: np.ndarray, mu0: np.ndarray, record: bool = False):
            """RK4 over every segment (each on its own: multiple shooting), with
            the 2x2 sensitivity: the ends (2, S), Φ (2, 2, S) and, recorded,
            the states (ψ, μ) at each step, (per + 1, 2, S)."""
            paths = [[(p, m)] if record else None for p, m in zip(psi0, mu0)]
            ends = np.array([segment(float(psi0[j]), float(mu0[j]), j, paths[j])
                             for j in range(nseg)]).T           # (6, S)
            path = np.array(paths).transpose(1, 2, 0) if record else None
            return ends[:2], ends[2:].reshape(2, 2, nseg), path

        # unknowns: μ_0, then (ψ_j, μ_j) at the start of segments j = 1..S-1
        psi_g, m_g = resample(guess, np.arange(nseg) / nseg)
        z = np.concatenate([[m_g[0] * L / ei_ref],
                            np.stack([psi_g[1:], m_g[1:] * L / ei_ref], 1).ravel()])

        def unpack(z):
            psi0 = np.concatenate([[0.0], z[1::2]])
            mu0 = np.concatenate([[z[0]], z[2::2]])
            return psi0, mu0

        col = [[None, 0]] + [[2 * j - 1, 2 * j] for j in range(1, nseg)]  # (ψ_j, μ_j) columns

        def residual(z):
            psi0, mu0 = unpack(z)
            y, phi, _ = shoot(psi0, mu0)
            n = 2 * nseg - 1
            r, jac = np.empty(n), np.zeros((n, n))
            for j in range(nseg):
                last = j == nseg - 1
                for row, comp in ([(n - 1, 1)] if last else [(2 * j, 0), (2 * j + 1, 1)]):
                    r[row] = y[comp, j]
                    for c in (0, 1):
                        if col[j][c] is not None:
                            jac[row, col[j][c]] = phi[comp, c, j]
                    if not last:  # continuity with the next segment's start
                        r[row] -= z[col[j + 1][comp]]
                        jac[row, col[j + 1][comp]] = -1.0
            return r, jac

        res = damped_newton(residual, z, self.tolerance, self.max_iter, min_damping=1e-3,
                            relative=True, residual_tolerance=1e-14 * max(1.0, kappa))
        z = res.x
        psi0, mu0 = unpack(z)
        _, _, traj = shoot(psi0, mu0, record=True)      # (per+1, 2, S)
        psi = np.concatenate([traj[:-1, 0, j] for j in range(nseg)] + [traj[-1:, 0, -1]])
        mu = np.concatenate([traj[:-1, 1, j] for j in range(nseg)] + [traj[-1:, 1, -1]])
        u = np.arange(psi.size) * h
        x, y = _integrate_xy(psi, mu * ei_ref / stiff.ei(u * L), h)
        return BeamSolution(load, self.name, u * L, x * L, y * L, psi, mu * ei_ref / L,
                            error_estimate=np.inf, converged=res.converged,
                            branch=classify_branch(alpha, psi), iterations=res.iterations,
                            message=res.message, extras={"segments": nseg, "steps": nseg * per})


def _integrate_xy(psi: np.ndarray, dpsi: np.ndarray, h: float) -> tuple[np.ndarray, np.ndarray]:
    """x = ∫cos ψ, y = ∫sin ψ on a uniform grid, fourth order.

    ψ between grid points is the cubic Hermite interpolant of ψ and ψ'
    (both known at the nodes); each step is integrated with 3-point
    Gauss-Legendre, so the error is O(h^4) like RK4's.
    """
    g = np.array([-np.sqrt(3 / 5), 0.0, np.sqrt(3 / 5)])
    w = np.array([5 / 9, 8 / 9, 5 / 9]) / 2
    t = (g + 1) / 2
    h00, h10 = 2 * t ** 3 - 3 * t ** 2 + 1, t ** 3 - 2 * t ** 2 + t
    h01, h11 = -2 * t ** 3 + 3 * t ** 2, t ** 3 - t ** 2
    p0, p1 = psi[:-1, None], psi[1:, None]
    d0, d1 = dpsi[:-1, None] * h, dpsi[1:, None] * h
    mid = h00 * p0 + h10 * d0 + h01 * p1 + h11 * d1
    dx = h * (np.cos(mid) @ w)
    dy = h * (np.sin(mid) @ w)
    return np.concatenate([[0.0], np.cumsum(dx)]), np.concatenate([[0.0], np.cumsum(dy)])
