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
from design.physics.beam import BeamSolution, PointLoad, normalise_angle, straight_solution
from design.solvers.beam.base import BeamMethod
from design.solvers.beam.small_deflection import picard, picard_error

_EPS = np.finfo(float).eps


def _cos_zeta_p(alpha: np.ndarray, d: np.ndarray, psi0: np.ndarray) -> np.ndarray:
    """p cos ζ = sqrt(p^2 - sin^2(α/2)) = sqrt(sin(ψ0/2) sin(α + ψ0/2)), without cancellation.

    α + ψ0/2 = π - (d + ψ0/2): its sine is taken from whichever form is far
    from a multiple of π, so that near-tension (α → π) keeps its digits.
    """
    half = alpha + psi0 / 2
    s = np.where(half <= np.pi / 2, np.sin(half), np.sin(d + psi0 / 2))
    return np.sqrt(np.maximum(np.sin(psi0 / 2) * s, 0.0))


def kl_of(alpha: np.ndarray, d: np.ndarray, psi0: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """kL on the primary branch and d(kL)/dψ0, vectorised.

    0 ≤ α < π; ``d`` and ``psi0`` are two forms of the same unknown
    (d + ψ0 = π - α), each accurate where it is small.
    """
    s_half = np.sin(alpha / 2)
    m1 = np.sin(d / 2) ** 2                     # 1 - p^2
    m = 1.0 - m1
    p = np.cos(d / 2)
    # ζ from sin ζ = sin(α/2)/p, cos ζ = sqrt(p^2 - sin^2(α/2))/p, both accurate
    cz_num = _cos_zeta_p(alpha, d, psi0)
    zeta = np.arctan2(s_half, cz_num)
    chi = np.arctan2(cz_num, s_half * np.sin(d / 2))   # K - F(ζ) = F(χ)
    k_full = special.ellipkm1(m1)
    f_zeta = special.ellipkinc(zeta, m)
    # of the two amplitudes, the one farther from π/2 is insensitive to the
    # rounding of m near 1 and free of cancellation
    kl = np.where(chi < zeta, special.ellipkinc(chi, m), k_full - f_zeta)
    # d(kL)/dv with v = α + ψ0 (dm/dv = sin(v)/2 = sin(d)/2)
    e_full = special.ellipe(m)
    e_zeta = special.ellipeinc(zeta, m)
    with np.errstate(divide="ignore", invalid="ignore"):
        dk_dm_minus_df_dm = ((e_full - e_zeta) - m1 * (k_full - f_zeta)) / (2 * m * m1) \
            + np.sin(2 * zeta) / (4 * m1 * np.cos(alpha / 2))
        # tan ζ cot(v/2) = (sin ζ / cos ζ)(cos(v/2) / sin(v/2)), cos(v/2) = sin(d/2), sin(v/2) = p
        tan_zeta_cot = np.divide(s_half * np.sin(d / 2), cz_num * p)
    dkl_dv = dk_dm_minus_df_dm * np.sin(d) / 2 + tan_zeta_cot / (2 * np.cos(alpha / 2))
    return kl, dkl_dv


def solve_root(kl: np.ndarray, alpha: np.ndarray, tol: float = 1e-15, max_iter: int = 100
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Solve eq. (2.12) on the primary branch, vectorised over loads.

    The unknown is carried as the logarithm of whichever of ψ0 and
    d = π - α - ψ0 is small (ψ0 for kL < 1.5, d beyond), so that both
    F → 0 (ψ0 ~ (kL)^2/2 far below eps π) and huge loads (d ~ 8 e^(-kL)) keep
    full relative precision. Safeguarded Newton with a bracket, bisection
    where Newton leaves it. Requires 0 ≤ α < π and, for α = 0, kL > π/2.

    Returns
    -------
    d, psi0 : ndarray
        The two forms of the root (rad).
    last_step : ndarray
        Size of the last update of the log-variable (convergence measure).
    iterations : ndarray of int
    """
    kl = np.asarray(kl, dtype=float)
    alpha = np.asarray(alpha, dtype=float)
    total = np.pi - alpha
    small_load = (kl < 1.5) & (alpha > 0)         # buckling (α = 0) starts at ψ0 = 0 only in the limit
    # ψ0 (or d) as a function of z; kL increases with ψ0, decreases with d
    sign = np.where(small_load, 1.0, -1.0)
    lo = np.full_like(kl, np.log(1e-300))
    hi = np.log(total)
    psi_small = np.minimum(0.5 * kl ** 2 * np.sin(alpha), 0.9 * total)
    d_large = 8.0 * np.exp(-kl - np.arctanh(np.minimum(np.sin(alpha / 2), 1 - 1e-16)))
    guess = np.where(small_load, np.maximum(psi_small, 1e-300),
                     np.clip(d_large, 1e-300, 0.5 * total))
    z = np.clip(np.log(guess), lo, hi)

    def forms(zz, idx):
        v = np.exp(zz)
        other = total[idx] - v
        return (np.where(small_load[idx], other, v), np.where(small_load[idx], v, other))

    step = np.full_like(kl, np.inf)
    its = np.zeros(kl.shape, dtype=int)
    active = np.ones(kl.shape, dtype=bool)
    for _ in range(max_iter):
        if not active.any():
            break
        idx = np.flatnonzero(active)
        za, ta = z[idx], kl[idx]
        d_a, psi_a = forms(za, idx)
        val, dval_dv = kl_of(alpha[idx], d_a, psi_a)
        dval = np.where(small_load[idx], psi_a, -d_a) * dval_dv      # d(kL)/dz
        r = val - ta
        solved = np.abs(r) <= 4 * _EPS * ta
        above = sign[idx] * r > 0                    # z too far towards larger kL
        lo_a = np.where(above, lo[idx], za)
        hi_a = np.where(above, za, hi[idx])
        # bracket in z: kL(z) - target changes sign between lo_a and hi_a
        with np.errstate(divide="ignore", invalid="ignore"):
            znew = za - r / dval
        bad = ~np.isfinite(znew) | (znew < lo_a) | (znew > hi_a)
        znew = np.where(solved, za, np.where(bad, 0.5 * (lo_a + hi_a), znew))
        st = np.abs(znew - za)
        z[idx], lo[idx], hi[idx], step[idx] = znew, lo_a, hi_a, st
        its[idx] += 1
        done = solved | (st <= tol * np.maximum(1.0, np.abs(znew)))
        active[idx[done]] = False
    d, psi0 = forms(z, np.arange(kl.size))
    return d, psi0, step, its


def shape(alpha: np.ndarray, d: np.ndarray, psi0: np.ndarray, at: np.ndarray, n: int
          ) -> tuple[np.ndarray, ...]:
    """Primary-branch shapes at n points uniform in s, vectorised over loads.

    Arguments are 1-D arrays over loads (0 ≤ α < π), (d, ψ0) from
    :func:`solve_root`. Returns s, x, y, ψ and the curvature M/EI (1/m), each
    of shape (loads, n), along [0, at].
    """
    alpha, d, psi0, at = (np.asarray(v, dtype=float)[:, None] for v in (alpha, d, psi0, at))
    # k consistent with the root (not the requested kL): the shape is then the
    # exact one of a load within rounding of the requested one
    k = kl_of(alpha[:, 0], d[:, 0], psi0[:, 0])[0][:, None] / at
    m = 1.0 - np.sin(d / 2) ** 2
    p = np.cos(d / 2)
    zeta = np.arctan2(np.sin(alpha / 2), _cos_zeta_p(alpha, d, psi0))
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


#: below this kL the closed form's cancellations cost more than they are worth
#: (the relative error of y grows like eps/(kL)^2); Picard steps from linear
#: theory are exact there
TINY_KL = 1e-2


def reverse_branch_exists(kl: np.ndarray, alpha: np.ndarray) -> np.ndarray:
    """Whether a uniform beam has a second, reverse-bent equilibrium (per load).

    ``kl`` = L sqrt(F/EI); ``alpha`` the load direction (any sign).
    """
    kl, a_abs = np.asarray(kl, dtype=float), np.abs(np.asarray(alpha, dtype=float))
    out = np.zeros(kl.shape, dtype=bool)
    may_fold = (kl > np.pi / 2) & (a_abs < np.pi)
    if may_fold.any():     # the threshold depends on α only: once per distinct α
        angles, inverse = np.unique(a_abs[may_fold], return_inverse=True)
        out[may_fold] = kl[may_fold] >= secondary_threshold(angles)[inverse]
    return out


class FrischFay(BeamMethod):
    """Closed-form uniform elastica; vectorised over loads (``nodes``: shape points).

    For kL < 0.01 the closed form loses digits to cancellation; there the
    linear solution refined by three Picard steps is returned (relative
    error ~(kL)^6 < 1e-12, estimated from the last steps).
    """

    name = "frisch-fay"
    order = None
    default_nodes = 21

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
        tiny = (kl > 0) & (kl < TINY_KL) & (a_abs > 0) & (a_abs < np.pi)
        bent = (kl >= TINY_KL) & (a_abs < np.pi) & ((a_abs > 0) | (kl > np.pi / 2))
        d, psi0, step, its = solve_root(kl[bent], a_abs[bent])
        s, x, y, psi, curv = shape(a_abs[bent], d, psi0, at[bent], self.nodes)
        sign = np.where(alpha[bent] < 0, -1.0, 1.0)[:, None]
        # root step, plus rounding: the shape formulas divide O(1) sums by k, so
        # their error grows like eps/kL for tiny loads
        klb = kl[bent]
        err = (step * np.minimum(d, psi0) + 64 * _EPS * (1 + klb + 1 / klb)) * at[bent]
        second = reverse_branch_exists(kl[bent], a_abs[bent])
        out, j = [], 0
        for i, ld in enumerate(loads):
            if tiny[i]:
                out.append(self._tiny(ld, ei))
                continue
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

    def _tiny(self, load: PointLoad, ei: float) -> BeamSolution:
        L = load.at
        s = np.linspace(0.0, L, max(self.nodes, 201))
        fy = load.components[1]
        psi_lin = fy / ei * (L * s - s ** 2 / 2)
        steps = picard(s, psi_lin, load, self.finger.stiffness, 4)
        x, y, psi, moment = steps[-1]
        err = picard_error([(it[0][-1], it[1][-1]) for it in steps[-3:]])
        return BeamSolution(load, self.name, s, x, y, psi, moment,
                            error_estimate=err + s.size * _EPS * L, converged=True,
                            branch="primary", multiple_equilibria=False,
                            message="kL < 0.01: linear theory refined by Picard steps")
