"""Frisch-Fay closed form of the uniform elastica (thesis eqs. 2.9-2.12).

With k = sqrt(F/EI), α1 = ψ + α and p = sin((α + ψ0)/2):

    k L = K(p) - F(ζ|p),   sin ζ = sin(α/2) / p                    (2.12)

Precision. The root is sought in d = π - α - ψ0 (how far the load point's
tangent is from the force line), not in p: for large kL, d ~ 8 e^(-kL) is a
tiny number that p = cos(d/2) cannot carry, and K is evaluated from the
complementary parameter 1 - p^2 = sin^2(d/2). For small loads the
difference K - F(ζ) cancels; there the identity K - F(ζ) = F(χ) with
tan χ = cot ζ / cos(v/2) (v = α + ψ0) is used instead.

Branches. For 0 < α < π the *primary* branch (α1 increasing, the finger bent
the way the transverse force pushes) exists for every load and is the one
connected to F = 0. A *secondary* branch bent the other way exists past a
fold when kL ≥ K(p) + F(asin(sin(α/2)/p)|p) for some p; its existence is
reported, not returned. α < 0 is the mirror image; α = 0 is straight for
kL ≤ π/2 and buckled (+y by convention) beyond; α = π is pure tension.

References
----------
Frisch-Fay, R. (1962) Flexible Bars. Thesis §2.1, MODEL.md §2.1.
"""

from __future__ import annotations

import numpy as np
from scipy import special

from design.errors import MethodUnsupportedError
from design.physics.beam import BeamSolution, normalise_angle, straight_solution
from design.solve.beam.base import BeamMethod

_EPS = np.finfo(float).eps


def _cos_zeta_p(alpha: np.ndarray, d: np.ndarray) -> np.ndarray:
    """p cos ζ = sqrt(p^2 - sin^2(α/2)) = sqrt(sin(ψ0/2) sin(α + ψ0/2)), without cancellation.

    α + ψ0/2 = π - (d + ψ0/2): its sine is taken from whichever form is far
    from a multiple of π, so that near-tension (α → π) keeps its digits.
    """
    psi0 = np.pi - alpha - d
    half = alpha + psi0 / 2
    s = np.where(half <= np.pi / 2, np.sin(half), np.sin(d + psi0 / 2))
    return np.sqrt(np.maximum(np.sin(psi0 / 2) * s, 0.0))


def _kl_of_d(d: np.ndarray, alpha: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """kL and d(kL)/d(ln d) for the primary branch, vectorised; 0 ≤ α < π, 0 < d < π - α."""
    s_half = np.sin(alpha / 2)
    m1 = np.sin(d / 2) ** 2                     # 1 - p^2
    m = 1.0 - m1
    p = np.cos(d / 2)
    # ζ from sin ζ = sin(α/2)/p, cos ζ = sqrt(p^2 - sin^2(α/2))/p, both accurate
    cz_num = _cos_zeta_p(alpha, d)
    zeta = np.arctan2(s_half, cz_num)
    chi = np.arctan2(cz_num, s_half * np.sin(d / 2))   # K - F(ζ) = F(χ)
    k_full = special.ellipkm1(m1)
    f_zeta = special.ellipkinc(zeta, m)
    # of the two amplitudes, the one farther from π/2 is insensitive to the
    # rounding of m near 1 and free of cancellation
    kl = np.where(chi < zeta, special.ellipkinc(chi, m), k_full - f_zeta)
    # derivative d(kL)/dv, v = π - d  (dm/dv = sin(v)/2 = sin(d)/2)
    e_full = special.ellipe(m)
    e_zeta = special.ellipeinc(zeta, m)
    dk_dm_minus_df_dm = ((e_full - e_zeta) - m1 * (k_full - f_zeta)) / (2 * m * m1) \
        + np.sin(2 * zeta) / (4 * m1 * np.cos(alpha / 2))
    # tan ζ cot(v/2) = (sin ζ / cos ζ)(cos(v/2) / sin(v/2)), cos(v/2) = sin(d/2), sin(v/2) = p
    tan_zeta_cot = np.divide(s_half * np.sin(d / 2), cz_num * p,
                             out=np.full_like(d, np.inf), where=cz_num > 0)
    dkl_dv = dk_dm_minus_df_dm * np.sin(d) / 2 + tan_zeta_cot / (2 * np.cos(alpha / 2))
    return kl, -d * dkl_dv


def solve_d(kl: np.ndarray, alpha: np.ndarray, tol: float = 1e-15, max_iter: int = 100
            ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Solve eq. (2.12) for d = π - α - ψ0 on the primary branch, vectorised.

    Safeguarded Newton in ln d with a bracket, bisection where Newton leaves
    it. Requires 0 ≤ α < π and, for α = 0, kL > π/2.

    Returns
    -------
    d : ndarray
        π - α - ψ0 (rad).
    last_step : ndarray
        Size of the last update of ln d (convergence measure).
    iterations : ndarray of int
    """
    kl = np.asarray(kl, dtype=float)
    alpha = np.asarray(alpha, dtype=float)
    upper = np.pi - alpha
    lo = np.full_like(kl, np.log(1e-150))      # ln d where kL(d) > target (kL ≈ 345)
    hi = np.log(upper)                          # ln d where kL(d) ≤ target (kL(π-α) = 0)
    # initial guess: small-load (ψ0 = (kL)^2 sin α / 2) or large-load asymptote
    psi_small = np.minimum(0.5 * kl ** 2 * np.sin(alpha), 0.9 * upper)
    d_large = 8.0 * np.exp(-kl - np.arctanh(np.minimum(np.sin(alpha / 2), 1 - 1e-16)))
    d0 = np.where(kl < 1.5, upper - psi_small, np.minimum(d_large, 0.5 * upper))
    z = np.clip(np.log(np.maximum(d0, 1e-150)), lo, hi)
    step = np.full_like(kl, np.inf)
    its = np.zeros(kl.shape, dtype=int)
    active = np.ones(kl.shape, dtype=bool)
    for _ in range(max_iter):
        if not active.any():
            break
        idx = np.flatnonzero(active)
        za, aa, ta = z[idx], alpha[idx], kl[idx]
        val, dval = _kl_of_d(np.exp(za), aa)
        r = val - ta
        solved = np.abs(r) <= 4 * _EPS * np.maximum(ta, 1.0)
        lo_a = np.where(r > 0, za, lo[idx])
        hi_a = np.where(r <= 0, za, hi[idx])
        with np.errstate(divide="ignore", invalid="ignore"):
            znew = za - r / dval
        bad = ~np.isfinite(znew) | (znew < lo_a) | (znew > hi_a)
        znew = np.where(solved, za, np.where(bad, 0.5 * (lo_a + hi_a), znew))
        st = np.abs(znew - za)
        z[idx], lo[idx], hi[idx], step[idx] = znew, lo_a, hi_a, st
        its[idx] += 1
        done = solved | (st <= tol * np.maximum(1.0, np.abs(znew)))
        active[idx[done]] = False
    return np.exp(z), step, its


def shape(alpha: np.ndarray, d: np.ndarray, at: np.ndarray, n: int) -> tuple[np.ndarray, ...]:
    """Primary-branch shapes at n points uniform in s, vectorised over loads.

    Arguments are 1-D arrays over loads (0 ≤ α < π), d from :func:`solve_d`. Returns s, x, y, ψ and
    the curvature M/EI (1/m), each of shape (loads, n), along [0, at].
    """
    alpha, d, at = (np.asarray(v, dtype=float)[:, None] for v in (alpha, d, at))
    # k consistent with d (not the requested kL): the root carries ~eps/ψ0
    # relative error for tiny loads, and dividing by the requested k would
    # turn it into a position error of that size times L.
    k = _kl_of_d(d[:, 0], alpha[:, 0])[0][:, None] / at
    m = 1.0 - np.sin(d / 2) ** 2
    p = np.cos(d / 2)
    zeta = np.arctan2(np.sin(alpha / 2), _cos_zeta_p(alpha, d))
    s = at * np.linspace(0.0, 1.0, n)[None, :]
    e_zeta = special.ellipeinc(zeta, m)
    # amplitude ξ(s) from the tip: F(π/2) - F(ξ) = k (L - s), so with
    # w = k (L - s): sin ξ = cn w / dn w, cos ξ = k' sn w / dn w
    sn, cn, dn, _ = special.ellipj(k * (at - s), m)
    xi = np.arctan2(cn / dn, np.sin(d / 2) * sn / dn)
    xi[:, 0] = zeta[:, 0]
    h = 2 * (special.ellipeinc(xi, m) - e_zeta) - k * s
    ccz = np.cos(zeta) - np.cos(xi)
    x = (2 * p * np.sin(alpha) * ccz + h * np.cos(alpha)) / k
    y = (2 * p * np.cos(alpha) * ccz - h * np.sin(alpha)) / k
    # α1/2 = atan2(p sin ξ, sqrt(1 - p² sin² ξ)); 1 - p² sin² ξ = m1 + m cos² ξ keeps
    # its digits where arcsin(p sin ξ) ≈ π/2 would lose half of them
    psi = 2 * np.arctan2(p * np.sin(xi), np.sqrt(np.sin(d / 2) ** 2 + m * np.cos(xi) ** 2)) - alpha
    psi[:, 0] = 0.0
    curvature = 2 * k * p * np.cos(xi)
    return s, x, y, psi, curvature


def secondary_threshold(alpha: np.ndarray, iterations: int = 60) -> np.ndarray:
    """Smallest kL at which a secondary (reverse-bent) equilibrium exists, 0 ≤ α < π.

    min over p in (sin(α/2), 1) of K(p) + F(asin(sin(α/2)/p) | p), by golden
    section (the function is unimodal in p), vectorised over α.
    """
    s_half = np.sin(np.asarray(alpha, dtype=float) / 2)

    def f(q):
        p = s_half + (1 - s_half) * q
        ratio = np.divide(s_half, p, out=np.zeros_like(p), where=p > 0)
        return special.ellipk(p * p) + special.ellipkinc(np.arcsin(np.minimum(ratio, 1.0)), p * p)

    a, b = np.zeros_like(s_half), np.full_like(s_half, 1 - 1e-12)
    g = (np.sqrt(5) - 1) / 2
    c, e = b - g * (b - a), a + g * (b - a)
    fc, fe = f(c), f(e)
    for _ in range(iterations):
        left = fc < fe
        b = np.where(left, e, b)
        a = np.where(left, a, c)
        c, e = b - g * (b - a), a + g * (b - a)
        fc, fe = f(c), f(e)
    return np.minimum(np.minimum(fc, fe), f(np.zeros_like(s_half)))


class FrischFay(BeamMethod):
    """Closed-form uniform elastica; vectorised over loads (``nodes``: shape points)."""

    name = "frisch-fay"
    order = None
    default_nodes = 41

    def check(self) -> list[str]:
        if not self.finger.stiffness.uniform:
            return ["frisch-fay is the closed form for a uniform EI; this finger's EI varies "
                    "along its length (use shooting, fdm or collocation)"]
        return []

    def solve(self, loads):
        if not self.finger.stiffness.uniform:
            raise MethodUnsupportedError(self.check()[0])
        ei = float(self.finger.stiffness.ei(0.0))
        loads = list(loads)
        alpha = np.array([normalise_angle(ld.alpha) for ld in loads])
        at = np.array([ld.at for ld in loads])
        kl = at * np.sqrt(np.array([ld.force for ld in loads]) / ei)
        a_abs = np.abs(alpha)
        bent = (kl > 0) & (a_abs < np.pi) & ((a_abs > 0) | (kl > np.pi / 2))
        d, step, its = solve_d(kl[bent], a_abs[bent])
        s, x, y, psi, curv = shape(a_abs[bent], d, at[bent], self.nodes)
        sign = np.where(alpha[bent] < 0, -1.0, 1.0)[:, None]
        # root step, plus rounding: the shape formulas divide O(1) sums by k, so
        # their error grows like eps/kL for tiny loads (measured: 4e-15 m at kL = 0.01)
        klb = kl[bent]
        err = (step * d + 64 * _EPS * (1 + klb + 1 / klb)) * at[bent]
        may_fold = kl[bent] > np.pi / 2
        second = np.zeros(d.shape, dtype=bool)
        second[may_fold] = kl[bent][may_fold] >= secondary_threshold(a_abs[bent][may_fold])
        out, j = [], 0
        for i, ld in enumerate(loads):
            if not bent[i]:
                msg = ("axial compression below the Euler load (kL ≤ π/2)"
                       if a_abs[i] == 0 and kl[i] > 0 else "")
                out.append(straight_solution(ld, self.name, self.nodes, "straight", msg))
                continue
            out.append(BeamSolution(
                ld, self.name, s[j], x[j], sign[j] * y[j], sign[j] * psi[j],
                sign[j] * ei * curv[j], error_estimate=float(err[j]), converged=True,
                branch="buckled+" if alpha[i] == 0 else "primary", iterations=int(its[j]),
                multiple_equilibria=bool(second[j]),
                extras={"kL": float(kl[i]), "p": float(np.cos(d[j] / 2))}))
            j += 1
        return out
