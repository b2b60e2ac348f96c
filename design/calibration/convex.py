"""The convex fit of a compliance profile, its weight, and its confidence band.

With the measurements linear in the knot compliances, y = K c (see
:mod:`design.calibration.kernel`), the fit is the quadratic program

    minimise   ‖(K c - y) / σ‖² + λ ‖D c / c_ref‖²
    subject to c ≥ 0        (and c_(j+1) ≥ c_j for a finger that only softens
                             towards its tip: ``monotone = "decreasing"`` EI)

with σ the stated measurement noise, D the second differences on the knots
(a roughness penalty) and c_ref a scale (the best uniform compliance). It is
a cvxpy problem solved by Clarabel: an interior-point method that solves a
QP's quadratic objective directly (no cone reformulation) to 1e-8 relative
accuracy, where OSQP (ADMM, first order) stops at its 1e-5 tolerances (as
cvxpy sets them) and converges slowly past them: the weight's choice
compares the residuals of neighbouring weights, which needs the former. It
is also free, installed with cvxpy, and deterministic.

The weight λ is not a constant: it is chosen among a log-spaced grid by a
stated rule,

* ``gcv`` (default): generalised cross-validation, the λ minimising
  V(λ) = m ‖r‖² / (m - tr H)² (Craven & Wahba 1979), where r are the
  σ-scaled residuals of m measurements (of the constrained solution) and
  H = A (AᵀA + λ DᵀD)⁻¹ Aᵀ the influence matrix of the unconstrained
  problem. Counting the constraints active at a solution as equalities (the
  active-set influence matrix) does not work: with a monotone
  profile it credits every flat stretch the constraints clip as saved
  degrees of freedom, and GCV then picks weights 10⁴ times smaller whose
  wiggles only the constraints hold (EI errors several times larger on the
  thesis finger);
* ``l-curve``: the corner of (log ‖r‖, log ‖D c‖), the point of largest
  curvature (Hansen 1992).

The band is Wahba's (1983) Bayesian one: Cov(c) = σ̂² (AᵀA + λDᵀD)⁻¹
(scaled), with σ̂² = ‖r‖² / (m - tr H), the noise the residuals show
(relative to the stated σ); the constraints are left out of it, so that a
bound active at the solution does not make its neighbourhood look certain.
It reflects the data's sensitivity to each knot: where no measurement
depends on c the band is as wide as the penalty leaves it.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import cvxpy as cp
import numpy as np

#: the rules that pick the smoothing weight
WEIGHT_RULES = ("gcv", "l-curve")
#: the solver cvxpy is asked for (see the module docstring)
SOLVER = "CLARABEL"
#: λ grid: this many decades below and above λ_0 = tr(AᵀA) / tr(DᵀD), points per decade
DECADES_BELOW, DECADES_ABOVE, PER_DECADE = 9, 4, 3
#: studentised residual beyond which a measurement is flagged as badly fitted
FLAG_LIMIT = 3.0
#: two-sided 95 % normal quantile, the band's half-width in standard deviations
BAND_Z = 1.96


@dataclass
class WeightedFit:
    """One solution of the QP at weight ``lam`` (scaled unknowns z = c / c_ref)."""

    lam: float
    z: np.ndarray
    residual: np.ndarray     # σ-scaled residuals, (m,)
    roughness: float         # ‖D z‖
    trace: float             # tr H, the fit's effective number of parameters
    hat: np.ndarray          # diag H, (m,)

    @property
    def gcv(self) -> float:
        m = self.residual.size
        dof = m - self.trace
        return m * float(self.residual @ self.residual) / dof ** 2 if dof > 0 else np.inf


@dataclass
class Selection:
    """A sweep of weights and the one its rule chose, with the sweep's cost,
    and the least-squares problem it was chosen on: min ‖A z - y‖² + λ ‖D z‖²
    (A = ``design``, the σ-scaled readings' sensitivity to the unknowns;
    D = ``penalty``)."""

    chosen: WeightedFit
    sweep: list[WeightedFit]
    rule: str
    solve_time_s: float       # every solve of the sweep (Clarabel with cvxpy's time, or Ipopt)
    setup_time_s: float       # building the problem (once)
    solves: int
    status: str               # the solver statuses met, e.g. "optimal"
    design: np.ndarray
    penalty: np.ndarray
    #: the band is taken at the chosen weight over this (1: at the chosen weight)
    band_undersmoothing: float = 1.0
    #: another weight's fit the data cannot tell from the chosen one: the band
    #: then also covers that fit and its own band (None: no other)
    alternative: Selection | None = None

    @property
    def noise_scale(self) -> float:
        """σ̂: the residuals' noise over the stated one (1 if the statement was right)."""
        r, dof = self.chosen.residual, self.chosen.residual.size - self.chosen.trace
        return float(np.sqrt(r @ r / dof)) if dof > 0 else float("nan")

    def z_sd(self, rows: np.ndarray | None = None) -> np.ndarray:
        """Standard deviations of the scaled unknowns (the band's, / 1.96), at
        the chosen weight over :attr:`band_undersmoothing`, widened where an
        :attr:`alternative` fit (its distance / 1.96 plus its own) needs it;
        with ``rows`` (indices into the readings used), those the band would
        have were only these readings taken (same weights, same noise scales)."""
        A = self.design if rows is None else self.design[rows]
        weight = self.chosen.lam / self.band_undersmoothing
        cov = np.linalg.pinv(A.T @ A + weight * self.penalty.T @ self.penalty, hermitian=True)
        sd = self.noise_scale * np.sqrt(np.clip(np.diag(cov), 0, None))
        if self.alternative is None:
            return sd
        gap = np.abs(self.alternative.chosen.z - self.chosen.z) / BAND_Z
        return np.maximum(sd, gap + self.alternative.z_sd(rows))

    def studentised(self) -> np.ndarray:
        """r_i / (σ̂ sqrt(1 - H_ii)) of every measurement the fit used."""
        lever = np.clip(1.0 - self.chosen.hat, 1e-12, None)
        return self.chosen.residual / (self.noise_scale * np.sqrt(lever))


@dataclass
class ProfileFit:
    """A fitted compliance profile: ``c`` (1/(N m²)) at ``knots`` (m), its
    standard deviation, the weight and how it was chosen, and the fit's
    predictions of the observations it used (indices ``used`` into the
    data's observations, σ-scaled residuals in ``selection``)."""

    method: str               # "small-deflection" or "elastica"
    knots: np.ndarray
    c: np.ndarray
    sd: np.ndarray            # standard deviation of c (1/(N m²)), or of ln c if ``log``
    c_ref: float
    selection: Selection
    used: list[int]
    predictions: np.ndarray
    log: bool = False

    def ei_band(self) -> tuple[np.ndarray, np.ndarray]:
        """The 95 % band of EI (N m²) at the knots: low, high (inf where the
        band of c reaches 0)."""
        if self.log:
            return np.exp(-BAND_Z * self.sd) / self.c, np.exp(BAND_Z * self.sd) / self.c
        low_c, high_c = self.c + BAND_Z * self.sd, self.c - BAND_Z * self.sd
        return 1.0 / low_c, np.where(high_c > 0, 1.0 / np.maximum(high_c, 1e-300), np.inf)

    @property
    def band(self) -> np.ndarray:
        """The band's relative half-width at each knot (see :meth:`relative`)."""
        return self.relative(self.sd)

    def band_from(self, rows: np.ndarray) -> np.ndarray:
        """The relative half-width the band would have were only the readings
        ``rows`` (indices into ``used``) taken."""
        scale = 1.0 if self.log else self.c_ref
        return self.relative(self.selection.z_sd(rows) * scale)

    def relative(self, sd: np.ndarray) -> np.ndarray:
        """BAND_Z sd / c; or, if ``log``, e^(BAND_Z sd) - 1, the band's upper
        side (the wider)."""
        if self.log:
            return np.expm1(BAND_Z * sd)
        return BAND_Z * sd / np.maximum(self.c, 1e-300)

    @property
    def lam(self) -> float:
        return self.selection.chosen.lam

    @property
    def studentised(self) -> np.ndarray:
        return self.selection.studentised()

    @property
    def flagged(self) -> np.ndarray:
        return np.abs(self.studentised) > FLAG_LIMIT


def roughness(n: int) -> np.ndarray:
    """The penalty's matrix on n uniformly spaced knot values: the second
    differences z_(j-1) - 2 z_j + z_(j+1), and the first differences at both
    ends, z_1 - z_0 and z_(n-1) - z_(n-2). The end rows make the smoothest
    continuation flat, not straight: where the data say nothing (the clamp's
    first millimetres, the finger past its last load) a straight
    continuation of the profile's trend runs into c = 0 (EI infinite) or
    keeps growing; a flat one keeps the last value the data support."""
    D = np.zeros((max(n - 2, 0) + 2, n))
    for j in range(n - 2):
        D[j, j:j + 3] = (1.0, -2.0, 1.0)
    D[-2, :2] = (-1.0, 1.0)
    D[-1, -2:] = (-1.0, 1.0)
    return D


class CompliancePQ:
    """The parametrised QP (built once, solved for every λ)."""

    def __init__(self, A: np.ndarray, y: np.ndarray, monotone: str | None):
        n = A.shape[1]
        self.A, self.y, self.D = A, y, roughness(n)
        self.monotone = monotone
        self.z = cp.Variable(n)
        self.lam = cp.Parameter(nonneg=True)
        cons = [self.z >= 0]
        if monotone == "decreasing":          # EI decreasing: c increasing
            cons.append(cp.diff(self.z) >= 0)
        elif monotone == "increasing":
            cons.append(cp.diff(self.z) <= 0)
        objective = cp.sum_squares(A @ self.z - y) + self.lam * cp.sum_squares(self.D @ self.z)
        self.problem = cp.Problem(cp.Minimize(objective), cons)

    def solve(self, lam: float) -> tuple[WeightedFit | None, str]:
        self.lam.value = lam
        try:
            self.problem.solve(solver=SOLVER)
        except cp.error.SolverError as exc:
            return None, f"solver error: {exc}"
        if self.problem.status not in ("optimal", "optimal_inaccurate") or self.z.value is None:
            return None, self.problem.status
        return self.analyse(lam, np.asarray(self.z.value)), self.problem.status

    def analyse(self, lam: float, z: np.ndarray) -> WeightedFit:
        return analyse(self.A, self.y, self.D, lam, z)


def analyse(A: np.ndarray, y: np.ndarray, D: np.ndarray, lam: float, z: np.ndarray
            ) -> WeightedFit:
    """The solution z of min ‖A z - y‖² + λ ‖D z‖² (under whatever constraints)
    with its residuals and the influence matrix of the unconstrained problem
    (see the module docstring)."""
    H = A @ np.linalg.pinv(A.T @ A + lam * D.T @ D, hermitian=True) @ A.T
    r = A @ z - y
    return WeightedFit(lam, z, r, float(np.linalg.norm(D @ z)), float(np.trace(H)),
                       np.diag(H).copy())


def weight_grid(A: np.ndarray, D: np.ndarray) -> np.ndarray:
    """Log-spaced weights around λ_0 = tr(AᵀA) / tr(DᵀD), where the penalty and
    the data weigh alike."""
    lam0 = np.trace(A.T @ A) / max(np.trace(D.T @ D), 1e-300)
    exps = np.arange(-DECADES_BELOW * PER_DECADE, DECADES_ABOVE * PER_DECADE + 1) / PER_DECADE
    return lam0 * 10.0 ** exps


def pick(sweep: list[WeightedFit], rule: str) -> WeightedFit:
    """The fit the rule chooses from a sweep in increasing λ."""
    if rule == "gcv":
        return min(sweep, key=lambda f: f.gcv)
    rho = np.log([max(np.linalg.norm(f.residual), 1e-300) for f in sweep])
    eta = np.log([max(f.roughness, 1e-300) for f in sweep])
    t = np.log([f.lam for f in sweep])
    r1, e1 = np.gradient(rho, t), np.gradient(eta, t)
    r2, e2 = np.gradient(r1, t), np.gradient(e1, t)
    curvature = (r1 * e2 - r2 * e1) / np.maximum((r1 ** 2 + e1 ** 2) ** 1.5, 1e-300)
    inner = slice(1, len(sweep) - 1)           # the ends have one-sided differences
    return sweep[1 + int(np.argmax(curvature[inner]))]


def select_weight(A: np.ndarray, y: np.ndarray, monotone: str | None, rule: str
                  ) -> Selection:
    """Solve the QP min ‖A z - y‖² + λ ‖D z‖² (z ≥ 0, monotone if asked) over
    the weight grid and pick λ by ``rule``."""
    t0 = time.perf_counter()
    qp = CompliancePQ(A, y, monotone)
    setup = time.perf_counter() - t0
    sweep, statuses = [], set()
    grid = weight_grid(A, qp.D)
    t0 = time.perf_counter()
    for lam in grid:
        fit, status = qp.solve(lam)
        statuses.add(status)
        if fit is not None:
            sweep.append(fit)
    elapsed = time.perf_counter() - t0
    if not sweep:
        raise RuntimeError(f"the convex fit failed at every weight ({', '.join(statuses)})")
    return Selection(pick(sweep, rule), sweep, rule, elapsed, setup, len(grid),
                     ", ".join(sorted(statuses)), A, qp.D)


def compliance_scale(K: np.ndarray, y: np.ndarray, sigma: np.ndarray) -> float:
    """c_ref: the uniform compliance (1/(N m²)) that fits the measurements best."""
    k1, yw = K.sum(axis=1) / sigma, y / sigma
    c = float(k1 @ yw / (k1 @ k1)) if k1 @ k1 > 0 else 0.0
    return c if c > 0 else 1.0


def fit_compliance(K: np.ndarray, y: np.ndarray, sigma: np.ndarray, knots: np.ndarray,
                   used: list[int], monotone: str | None = None, rule: str = "gcv"
                   ) -> ProfileFit:
    """Fit c ≥ 0 at ``knots`` to measurements y ≈ K c with noise σ.

    Parameters
    ----------
    K : (m, n) array
        Kernel rows (m or rad per 1/(N m²)), from :func:`design.calibration.kernel.kernel`.
    y, sigma : (m,) arrays
        Measured values and their stated standard deviations (m or rad).
    knots : (n,) array
        Knot arc lengths (m), uniformly spaced.
    used : list of int
        The observations the rows are (indices into the data's observations).
    monotone : None, "decreasing" or "increasing"
        How EI(s) may vary from base to tip.
    rule : one of :data:`WEIGHT_RULES`
    """
    c_ref = compliance_scale(K, y, sigma)
    sel = select_weight(K * (c_ref / sigma)[:, None], y / sigma, monotone, rule)
    c = sel.chosen.z * c_ref
    return ProfileFit("small-deflection", knots, c, sel.z_sd() * c_ref, c_ref, sel, used, K @ c)
