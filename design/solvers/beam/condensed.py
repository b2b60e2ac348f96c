"""Newton steps of the beam's collocation equations by condensing, in O(K) work.

The collocation equations (:mod:`design.solvers.beam.collocation`) of the
elastica z = (ψ, μ) on u in [0, 1], ψ' = e(u) μ, μ' = g(ψ), on an interval
of width h with start z_0 and collocation values z_1..z_d:

    Σ_r C[r, k] z_r / h - f(z_k) = defect_k            (k = 1..d)

Linearised, with N = (C_c^T)^-1 (C_c = C[1:, 1:]) and N C[0, 1:] = -1 (the
rows of C sum to zero), the ψ rows give the collocation increments of ψ from
those of μ, and the μ rows then leave a d x d system for δμ_c:

    δψ_c = δψ_0 + h N (a + E δμ_c)
    (I - h² N Q N E) δμ_c = δμ_0 + h N Q 1 δψ_0 + h N (b + h Q N a)

(a, b = -defects of the ψ and μ rows, E = diag(e), Q = diag(∂g/∂ψ) at the
collocation points). The interval's end follows by the end-value weights D,
continuity carries it to the next start, and ψ(0) = 0 leaves one unknown,
t = δμ(0), fixed by μ(1) = 0: every increment is affine in t and carried as
two columns, its part without t and its coefficient of t.

The increment is the exact Newton step of the whole system (to rounding): a
d x d solve per interval instead of a sparse factorisation of the
2 K (d+1) unknowns. Like shooting, it grows rounding by the linearised
solution's growth from the base (exp ∫ (e |∂g/∂ψ|)^½ du at most; about 30 for
the thesis finger at 30 N); the caller checks the residual it reaches.
"""

from __future__ import annotations

from typing import NamedTuple, Sequence

import casadi as ca
import numpy as np


class Interval(NamedTuple):
    """One mesh interval's part of the equations (CasADi SX)."""

    #: width in u
    h: ca.SX
    #: unknowns, 2 x (d+1): (ψ, μ) at the interval start, then at the collocation points
    z: ca.SX
    #: e = ∂ψ'/∂μ at the collocation points (d,)
    e: ca.SX
    #: ∂μ'/∂ψ at the collocation points (d,)
    q: ca.SX
    #: collocation defects, 2 x d: Σ_r C[r, k] z_r / h - f(z_k)
    defect: ca.SX


def condensed_step(intervals: Sequence[Interval], C: np.ndarray, D: np.ndarray) -> ca.SX:
    """Newton increment of the unknowns (laid out as w: the columns of each
    interval's z, interval by interval) for ψ(0) = 0, the collocation
    equations, continuity and μ(1) = 0; C and D as in ``legendre_tables``."""
    d = C.shape[0] - 1
    N = ca.DM(np.linalg.inv(C[1:, 1:].T))
    one = ca.DM.ones(d, 1)
    unit = ca.DM([[1, 0]])                  # a value without t, as its two columns
    psi0 = -intervals[0].z[0, 0] * unit     # ψ(0) = 0
    mu0 = ca.DM([[0, 1]])                   # δμ(0) = t
    rows = []
    for j, iv in enumerate(intervals):
        h, E, Q = iv.h, ca.diag(iv.e), ca.diag(iv.q)
        a, b = -iv.defect[0, :].T, -iv.defect[1, :].T
        S = ca.SX.eye(d) - h ** 2 * (N @ Q @ N @ E)
        rhs = h * (N @ (b + h * (Q @ N @ a))) @ unit + one @ mu0 + h * (N @ Q @ one) @ psi0
        mu_c = ca.solve(S, rhs)
        psi_c = one @ psi0 + h * (N @ (a @ unit + E @ mu_c))
        rows.append((psi0, mu0, psi_c, mu_c))
        end = iv.z @ ca.DM(D)
        psi_end = D[0] * psi0 + ca.DM(D[1:]).T @ psi_c
        mu_end = D[0] * mu0 + ca.DM(D[1:]).T @ mu_c
        if j < len(intervals) - 1:
            gap = intervals[j + 1].z[:, 0] - end          # continuity
            psi0, mu0 = psi_end - gap[0] * unit, mu_end - gap[1] * unit
        else:
            t = -(end[1] + mu_end[0]) / mu_end[1]         # μ(1) = 0
    # the increments at t, in the layout of w
    at_t = ca.vertcat(1, t)
    return ca.vertcat(*[ca.vec(ca.horzcat(ca.vertcat(psi0, psi_c) @ at_t,
                                          ca.vertcat(mu0, mu_c) @ at_t).T)
                        for psi0, mu0, psi_c, mu_c in rows])
