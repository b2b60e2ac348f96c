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
        e_all = ei_ref / stiff.ei(grid * L)

        def e_at(seg: np.ndarray, i: int, half: int) -> np.ndarray:
            return e_all[2 * (seg * per + i) + half]

        seg = np.arange(nseg)

        def shoot(psi0: np.ndarray, mu0: np.ndarray, record: bool = False):
            """RK4 over every segment in parallel, with the 2x2 sensitivity."""
            y = np.stack([psi0, mu0])                       # (2, S)
            phi = np.broadcast_to(np.eye(2)[:, :, None], (2, 2, nseg)).copy()
            path = [y.copy()] if record else None

            def f(y, e):
                return np.stack([y[1] * e, -kappa * np.sin(y[0] + alpha)])

            def jf(y, e, ph):
                # J = [[0, e], [-κ cos, 0]] applied to Φ (2, 2, S)
                c = -kappa * np.cos(y[0] + alpha)
                return np.stack([e * ph[1], c * ph[0]])

            for i in range(per):
                e0, e1, e2 = e_at(seg, i, 0), e_at(seg, i, 1), e_at(seg, i, 2)
                k1, j1 = f(y, e0), jf(y, e0, phi)
                y2, p2 = y + 0.5 * h * k1, phi + 0.5 * h * j1
                k2, j2 = f(y2, e1), jf(y2, e1, p2)
                y3, p3 = y + 0.5 * h * k2, phi + 0.5 * h * j2
                k3, j3 = f(y3, e1), jf(y3, e1, p3)
                y4, p4 = y + h * k3, phi + h * j3
                k4, j4 = f(y4, e2), jf(y4, e2, p4)
                y = y + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
                phi = phi + h / 6 * (j1 + 2 * j2 + 2 * j3 + j4)
                if record:
                    path.append(y.copy())
            return y, phi, path

        # unknowns: μ_0, then (ψ_j, μ_j) at the start of segments j = 1..S-1
        u_starts = seg / nseg
        psi_g, m_g = resample(guess, u_starts)
        z = np.concatenate([[m_g[0] * L / ei_ref], np.stack([psi_g[1:], m_g[1:] * L / ei_ref], 1).ravel()])

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
        _, _, path = shoot(psi0, mu0, record=True)
        traj = np.stack(path)                         # (per+1, 2, S)
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
