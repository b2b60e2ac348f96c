"""The large-deflection fit: EI(s) on the elastica, along a path of weights.

Unknowns: q = ln(c / c_ref) at the knots (see
:class:`design.calibration.elastica.ElasticaFitProblem`). The penalty is λ ‖D q‖²,
D the second differences of q: it leaves exponential profiles
EI = A e^(b s) (a moulded taper's shape, and the dominant term of the
thesis's eq. 2.33) free, so the smoothing does not pull a taper of any ratio
towards uniform, and unlike a penalty on c it cannot push EI to infinity.

The weight λ is found along a path: Ipopt solves at λ = 10^4 λ_0
(λ_0 = tr(JᵀJ) / tr(DᵀD) at the start), where
q is all but held to the penalty's null space (the best exponential
profile), then at λ half a decade smaller each time, each solve starting
from the last. At each solution the weight rule's criterion is evaluated on
the problem linearised there (J the residuals' Jacobian in q, the
collocation equations held):

* ``gcv``: V(λ) = m ‖r‖² / (m - tr H)², H = J (JᵀJ + λ DᵀD)⁻¹ Jᵀ;
* ``l-curve``: the largest curvature of (ln ‖r‖, ln ‖D q‖) along the path.

The path ends :data:`PATIENCE` steps after GCV's least value (smaller
weights only fit the noise), when a solve fails, or at 10^-9 λ_0; the rule
picks among the weights solved (GCV when fewer than three were, too few for
a curvature). Where GCV is least at the path's first weight, it also goes
on until m ln(V / V_least) exceeds :data:`SUPPORT` (m readings).

The band: the convex fit's Bayesian one on the problem linearised at the
chosen solution (in q, so a band on ln EI: EI e^(±1.96 sd)), but at a tenth
of the chosen weight (:data:`BAND_UNDERSMOOTHING`). GCV's curve is flat
near its least value, so the weight is uncertain by about a decade,
and at the chosen weight the smoothness prior alone holds the profile where
the readings say little: towards the tip, where the moment of every load
vanishes, the band at the chosen weight is narrower than the fit's error on
a strip of linearly tapered thickness (tests/fit_benches.py, "thickness-50";
benchmarks/fit_bench.py measures every bench's coverage). The fit itself is
the one at the chosen weight.

Where the chosen weight is the path's first, the fit is all but the best
exponential profile, and its band is that two-parameter fit's: it does not
say what else the readings allow. When ln EI bends where the markers cannot
see it (a thickness falling fastest at the clamp), an exponential explains
the readings within their noise and is off by more than that band. The
band then also covers the fit at the smallest weight whose GCV is still
within :data:`SUPPORT` of the least (m ln(V / V_least) ≤ 2, about the
difference in Akaike's criterion below which two models are taken as
equally supported) and that fit's own band: ln c ± max(1.96 sd, |Δ ln c| +
1.96 sd'). The rule was settled on the benches run before the fourth
held-out batch (tests/fit_benches.py, benchmarks/fit_bench.py).

Where it starts: :func:`design.calibration.elastica.uniform_fit`, the uniform EI
that fits the readings on the elastica. It needs no small-deflection fit (x
readings alone give that nothing to fit), and the path's first solve, at the
largest weight, is then a fit of two parameters from a nearby start;
benchmarks/fit_bench.py --starts compares it with starting from the
small-deflection fit.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from design.calibration.convex import ProfileFit, Selection, WeightedFit, analyse, pick
from design.calibration.data import FingerData
from design.calibration.elastica import ElasticaFitProblem, IpoptSolve
from design.physics.beam import BeamSolution

#: the path: from λ_0 10^TOP down to λ_0 10^BOTTOM in steps of STEP decades
TOP, BOTTOM, STEP = 4.0, -9.0, 0.5
#: the path ends this many steps after GCV's least value
PATIENCE = 2
#: the band is the Bayesian band at the chosen weight over this (see the
#: module docstring; tests/fit_benches.py's benches measure its coverage)
BAND_UNDERSMOOTHING = 10.0
#: GCV's support for another weight: m ln(V / V_least) up to this (see the
#: module docstring)
SUPPORT = 2.0


def curvature(n: int) -> np.ndarray:
    """The penalty's matrix on n uniformly spaced knot values of ln c: the
    second differences q_(j-1) - 2 q_j + q_(j+1)."""
    D = np.zeros((max(n - 2, 0), n))
    for j in range(n - 2):
        D[j, j:j + 3] = (1.0, -2.0, 1.0)
    return D


@dataclass
class Refinement:
    """The elastica fit and how it went: every Ipopt solve along the path
    (in order), the one chosen, why the path ended, the NLP's size and build
    time (s)."""

    fit: ProfileFit
    solves: list[IpoptSolve]
    chosen: int
    ended: str
    unknowns: int
    build_time_s: float
    #: the weight at which Ipopt failed and the path ended early (None: it did not)
    failed_at: float | None = None

    @property
    def success(self) -> bool:
        """Whether Ipopt converged at the chosen weight."""
        return 0 <= self.chosen < len(self.solves) and self.solves[self.chosen].success


@dataclass
class _Step:
    """One solved point of the path."""

    solve: IpoptSolve
    fit: WeightedFit
    predictions: np.ndarray
    jacobian: np.ndarray       # J: the σ-scaled residuals' sensitivity to q


def _support(path: list[_Step], i: int) -> float:
    """m ln(V_i / V_0): how much worse GCV finds path[i] than the path's first
    weight's fit."""
    return path[i].fit.residual.size * float(np.log(path[i].fit.gcv / path[0].fit.gcv))


def _alternative(path: list[_Step], statuses: str, D: np.ndarray) -> Selection | None:
    """The fit at the smallest weight after the path's first whose GCV is
    within :data:`SUPPORT` of it, every weight in between too (None: not even
    the second's is)."""
    last = 0
    while last + 1 < len(path) and _support(path, last + 1) <= SUPPORT:
        last += 1
    if last == 0:
        return None
    step = path[last]
    return Selection(step.fit, [step.fit], "gcv", 0.0, 0.0, 0, statuses, step.jacobian, D,
                     BAND_UNDERSMOOTHING)


def refine(data: FingerData, length: float, knots: np.ndarray, c_start: np.ndarray,
           c_ref: float, start: list[BeamSolution], monotone: str | None = None,
           rule: str = "gcv") -> Refinement:
    """The elastica fit of c = 1/EI at ``knots`` (m) from the profile
    ``c_start`` (1/(N m²)) and its load cases' solutions ``start``; c_ref
    (1/(N m²)) scales the unknowns. ``monotone`` and ``rule`` as in
    :func:`design.calibration.convex.fit_compliance`."""
    D = curvature(knots.size)
    problem = ElasticaFitProblem(data, length, knots, c_start, c_ref, monotone, start, D)
    x0 = problem.x.copy()
    _, J, _ = problem.linearised()
    lam0 = float(np.trace(J.T @ J) / np.trace(D.T @ D))
    weights = lam0 * 10.0 ** np.arange(TOP, BOTTOM - 1e-9, -STEP)
    solves: list[IpoptSolve] = []
    path: list[_Step] = []
    ended, failed_at = "it reached the smallest weight of the path", None
    t0 = time.perf_counter()
    for lam in weights:
        solves.append(problem.solve(lam))
        if not solves[-1].success:
            ended, failed_at = f"Ipopt failed at weight {lam:.3g} ({solves[-1].status})", lam
            break
        r, J, pred = problem.linearised()
        path.append(_Step(solves[-1], analyse(J, J @ problem.q - r, D, lam, problem.q.copy()),
                          pred, J))
        least = min(range(len(path)), key=lambda i: path[i].fit.gcv)
        if len(path) - 1 - least >= PATIENCE and (least > 0 or _support(path, -1) > SUPPORT):
            ended = f"GCV rose for {PATIENCE} steps past its least value" + \
                ("" if least > 0 else f" and by more than m ln(V / V_least) = {SUPPORT:g}")
            break
    elapsed = time.perf_counter() - t0
    if not path:                      # no solve converged: the start, reported as such
        problem.x = x0
        r, J, pred = problem.linearised()
        step = _Step(solves[-1], analyse(J, J @ problem.q - r, D, weights[0], problem.q.copy()),
                     pred, J)
        chosen, sweep = -1, [step.fit]
    else:
        sweep = [s.fit for s in path]
        best = pick(sweep, rule if len(path) >= 3 else "gcv")
        step = next(s for s in path if s.fit is best)
        chosen = next(i for i, s in enumerate(solves) if s is step.solve)
    statuses = ", ".join(sorted({s.status for s in solves}))
    selection = Selection(step.fit, sweep, rule, elapsed, problem.build_time_s, len(solves),
                          statuses, step.jacobian, D, BAND_UNDERSMOOTHING,
                          _alternative(path, statuses, D) if path and step is path[0] else None)
    fit = ProfileFit("elastica", knots, c_ref * np.exp(step.fit.z), selection.z_sd(), c_ref,
                     selection, list(range(len(data.observations))), step.predictions, log=True)
    return Refinement(fit, solves, chosen, ended, problem.unknowns, problem.build_time_s,
                      failed_at)
