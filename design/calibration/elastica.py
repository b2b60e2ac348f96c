"""The planar elastica at measured points, the uniform finger that fits the
readings best, and the refinement's nonlinear least-squares problem.

Predictions: each load case is solved by the toolkit's collocation method
(:class:`design.solvers.beam.collocation.Collocation`) and read at the measured
arc lengths by cubic Hermite interpolation of x, y (slopes cos ψ, sin ψ) and
ψ (slope M / EI) between its nodes; past the load point the finger is
straight.

The refinement's problem (:class:`ElasticaFitProblem`): the log-compliances
q = ln(c / c_ref) at the knots fitted to the readings on the collocated
elastica, solved simultaneously (every load case's collocation unknowns are
NLP unknowns, its collocation equations constraints) by Ipopt. The
transcription is the toolkit's
:class:`~design.solvers.beam.collocation.BeamTranscription` with the stiffness
:class:`~design.calibration.kernel.KnotCompliance` (c piecewise linear between the
knots, c = c_ref e^q at them: positive whatever step Ipopt tries); each
case's mesh has an interval edge at every knot (EI has a kink there) and at
every measured point inside the loaded span, so a prediction is a mesh
node's value, not an interpolation. Objective ½ ‖r / σ‖² + ½ λ ‖D q‖², D
the penalty's matrix (see :mod:`design.calibration.refinement`).

Ipopt is given the Gauss-Newton Hessian of the objective, Rᵀ R + λ DᵀD (R
the residuals' Jacobian in all unknowns), not the exact Hessian of the
Lagrangian: the generalised Gauss-Newton method of parameter estimation in
collocated differential equations (Bock 1983). The exact one, with the
collocation equations' curvature weighted by their multipliers, is
indefinite away from a small-residual solution, and Ipopt's inertia
correction then regularised it until the steps vanished ("error in step
computation") on the tuning benches of tests/fit_benches.py; the
Gauss-Newton one is positive semi-definite, so each step is a least-squares
step on the linearised elastica.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import casadi as ca
import numpy as np
import scipy.sparse as sp
from scipy.interpolate import CubicHermiteSpline
from scipy.optimize import minimize_scalar
from scipy.sparse.linalg import spsolve

from design.calibration.data import FingerData
from design.calibration.kernel import KnotCompliance
from design.physics.beam import BeamSolution, Finger
from design.physics.stiffness import UniformEI
from design.solvers.beam.collocation import Collocation, legendre_tables, transcription

#: collocation degree of the refinement's transcription (nodal order 2d = 6;
#: intervals are a few mm, so its error is far below any bench's noise)
DEGREE = 3
#: intervals of each case's mesh beyond those its knots and points need
SPARE_INTERVALS = 8
#: the uniform fit's grid: the EI at which the heaviest load's F a² / EI is
#: 10^k, k over this range in half decades (from barely bent to folded)
UNIFORM_DECADES = (-2.0, 2.0)


def points_on(sol: BeamSolution, finger: Finger, s: np.ndarray) -> dict[str, np.ndarray]:
    """x, y (m) and ψ (rad) of a solved finger at arc lengths ``s`` (m, up to
    the finger's length): cubic Hermite between the solution's nodes, a
    straight line past the load point."""
    s = np.asarray(s, dtype=float)
    nodes, keep = np.unique(sol.s, return_index=True)
    psi, moment = sol.psi[keep], sol.moment[keep]
    inside = np.minimum(s, sol.load.at)
    x = CubicHermiteSpline(nodes, sol.x[keep], np.cos(psi))(inside)
    y = CubicHermiteSpline(nodes, sol.y[keep], np.sin(psi))(inside)
    p = CubicHermiteSpline(nodes, psi, moment / finger.stiffness.ei(nodes))(inside)
    beyond = s - inside
    return {"x": x + beyond * np.cos(p), "y": y + beyond * np.sin(p), "psi": p}


def elastica_predictions(finger: Finger, data: FingerData, nodes: int = 16
                         ) -> tuple[np.ndarray, list[BeamSolution]]:
    """Every observation's value on the elastica of ``finger`` (in the order
    of ``data.observations``), and each load case's solution."""
    sols = Collocation(finger, nodes=nodes).solve(list(data.loads))
    out = np.empty(len(data.observations))
    for k, sol in enumerate(sols):
        idx = [i for i, o in enumerate(data.observations) if o.case == k]
        if not idx:
            continue
        pts = points_on(sol, finger, np.array([data.observations[i].s for i in idx]))
        for j, i in enumerate(idx):
            out[i] = pts[data.observations[i].quantity][j]
    return out, sols


@dataclass
class UniformFit:
    """The uniform EI (N m²) whose elastica fits the readings best, its load
    cases' solutions, the σ-scaled residuals' sum of squares, the elastica
    solves it took and its time (s)."""

    ei: float
    solutions: list[BeamSolution]
    chi2: float
    evaluations: int
    time_s: float


def uniform_fit(data: FingerData, length: float) -> UniformFit:
    """Least squares of one uniform EI on the elastica: the best of a log
    grid (:data:`UNIFORM_DECADES`), then Brent's method on ln EI within half
    a decade of it. Any readings do (x alone included); nothing is taken
    from the small-deflection model."""
    t0 = time.perf_counter()
    scale = max(ld.force * abs(np.sin(ld.alpha)) * ld.at ** 2 for ld in data.loads)
    seen: dict[float, tuple[float, list[BeamSolution]]] = {}

    def chi2(log_ei: float) -> float:
        pred, sols = elastica_predictions(Finger(length, UniformEI(float(np.exp(log_ei)))), data)
        value = float(np.sum(((pred - data.values) / data.sigmas) ** 2))
        if not (np.isfinite(value) and all(s.converged for s in sols)):
            value = np.inf
        seen[float(log_ei)] = (value, sols)
        return value

    lo, hi = UNIFORM_DECADES
    grid = np.log(scale) - np.log(10.0) * np.arange(lo, hi + 0.25, 0.5)
    best = min(grid, key=chi2)
    half = 0.5 * np.log(10.0)
    minimize_scalar(chi2, bounds=(best - half, best + half), method="bounded",
                    options={"xatol": 1e-4})
    log_ei = min(seen, key=lambda k: seen[k][0])
    value, sols = seen[log_ei]
    return UniformFit(float(np.exp(log_ei)), sols, value, len(seen), time.perf_counter() - t0)


def case_mesh(knots: np.ndarray, at: float, points: list[float], intervals: int
              ) -> np.ndarray:
    """Mesh edges (m) on [0, at] through every knot and measured point inside
    it (two closer than 1e-6 at are one edge: a near-empty interval would
    make the collocation equations singular), the longest interval halved
    until there are ``intervals``."""
    tol = 1e-6 * at
    inside = np.concatenate([knots, points])
    edges = [0.0]
    for e in np.sort(inside[(inside > tol) & (inside < at - tol)]):
        if e - edges[-1] > tol:
            edges.append(float(e))
    edges = np.array(edges + [at])
    while edges.size - 1 < intervals:
        k = int(np.argmax(np.diff(edges)))
        edges = np.insert(edges, k + 1, (edges[k] + edges[k + 1]) / 2)
    return edges


def edge_values(w, edges: np.ndarray, tables, K: int):
    """x, y (new unknowns, the first fixed at 0) and ψ at the mesh edges of
    one case, and the equations that tie x, y to the collocated ψ: each
    interval adds h Σ_r B_r (cos ψ_r, sin ψ_r) over its collocation points
    (the transcription's own quadrature, kept local so that the NLP's
    Hessian stays sparse instead of coupling every point to every slope).
    w holds (ψ, μ) at each interval's start and collocation points."""
    tau, _, D, B, _ = tables
    d = tau.size - 1
    start = 2 * (d + 1) * np.arange(K)                       # ψ at each interval's start
    inner = (start[:, None] + 2 * np.arange(1, d + 1)[None, :]).ravel()
    quad = sp.kron(sp.diags(np.diff(edges)), B[None, :])     # h_j B_r, (K, K d)
    quad = ca.DM(sp.csc_matrix(quad))
    psi_c = w[inner.tolist()]
    xs = ca.vertcat(0, ca.SX.sym("x", K))
    ys = ca.vertcat(0, ca.SX.sym("y", K))
    closure = ca.vertcat(xs[1:] - xs[:-1] - ca.mtimes(quad, ca.cos(psi_c)),
                         ys[1:] - ys[:-1] - ca.mtimes(quad, ca.sin(psi_c)))
    last = [start[-1] + 2 * r for r in range(d + 1)]
    psis = [w[int(i)] for i in start] + [ca.dot(ca.DM(D), w[last])]
    return xs, ys, psis, closure


@dataclass
class IpoptSolve:
    """One Ipopt solve of the refinement, at weight ``lam``."""

    lam: float
    status: str
    success: bool
    iterations: int
    time_s: float


class ElasticaFitProblem:
    """The refinement's NLP, built once; the weight λ is its parameter.

    Unknowns: q = ln(c / c_ref) at the knots, then for each load case its
    collocation unknowns and the x, y of its mesh edges. Objective
    ½ ‖r / σ‖² + ½ λ ‖D q‖² (D = ``penalty``); constraints: the collocation
    equations, the edges' quadrature and the monotonicity asked for. It
    starts from the profile ``c_start`` (1/(N m²) at ``knots``) and its load
    cases' solutions ``start``.
    """

    def __init__(self, data: FingerData, length: float, knots: np.ndarray,
                 c_start: np.ndarray, c_ref: float, monotone: str | None,
                 start: list[BeamSolution], penalty: np.ndarray, max_iter: int = 200):
        t0 = time.perf_counter()
        self.c_ref, self.n = c_ref, knots.size
        stiff0 = KnotCompliance(tuple(knots), tuple(c_start))
        finger0 = Finger(length, stiff0)
        obs = data.observations
        per_case = [[o.s for o in obs if o.case == k] for k in range(len(data.loads))]
        K = max(case_mesh(knots, ld.at, pts, 1).size - 1
                for ld, pts in zip(data.loads, per_case)) + SPARE_INTERVALS
        tr = transcription(stiff0, K, DEGREE)
        tables = legendre_tables(DEGREE)
        q = ca.SX.sym("q", self.n)
        lam = ca.SX.sym("lam")
        c = c_ref * ca.exp(q)
        ws, w0, G = [], [], []
        pred = [None] * len(obs)
        for k, (load, sol) in enumerate(zip(data.loads, start)):
            edges = case_mesh(knots, load.at, per_case[k], K)
            widths = np.diff(edges) / load.at
            ei_ref = stiff0.compliance_equivalent(load.at)
            w = ca.SX.sym(f"w{k}", tr.n_w)
            P = ca.vertcat(load.force, load.alpha, load.at, ei_ref, widths, c)
            G.append(tr.residual(w, P))
            xs, ys, psis, closure = edge_values(w, edges, tables, K)
            ws.append(ca.vertcat(w, xs[1:], ys[1:]))
            G.append(closure)
            w0.append(np.concatenate([tr.guess(sol, ei_ref, widths),
                                      *(points_on(sol, finger0, edges[1:])[v] for v in "xy")]))
            for i, o in enumerate(obs):
                if o.case != k:
                    continue
                e = int(np.argmin(np.abs(edges - min(o.s, load.at))))
                ahead = max(o.s - load.at, 0.0)          # past the load point: straight
                pred[i] = {"x": xs[e] + ahead * ca.cos(psis[e]),
                           "y": ys[e] + ahead * ca.sin(psis[e]), "psi": psis[e]}[o.quantity]
        pred_v = ca.vertcat(*pred)
        r = (pred_v - data.values) / data.sigmas
        D = ca.DM(penalty)
        f = 0.5 * ca.sumsqr(r) + 0.5 * lam * ca.sumsqr(ca.mtimes(D, q))
        wall = ca.vertcat(*ws)
        eqs = ca.vertcat(*G)
        g, lbg, ubg = [eqs], [np.zeros(eqs.shape[0])], [np.zeros(eqs.shape[0])]
        if monotone in ("decreasing", "increasing"):
            g.append(q[1:] - q[:-1])
            lo, hi = (0.0, np.inf) if monotone == "decreasing" else (-np.inf, 0.0)
            lbg.append(np.full(self.n - 1, lo))
            ubg.append(np.full(self.n - 1, hi))
        x_all = ca.vertcat(q, wall)
        g_all = ca.vertcat(*g)
        self.unknowns = int(x_all.shape[0])
        R = ca.jacobian(r, x_all)
        Dx = ca.horzcat(D, ca.DM(D.shape[0], x_all.shape[0] - self.n))
        gauss_newton = ca.mtimes(R.T, R) + lam * ca.mtimes(Dx.T, Dx)
        weight_f, weight_g = ca.SX.sym("lam_f"), ca.SX.sym("lam_g", g_all.shape[0])
        hessian = ca.Function("nlp_hess_l", [x_all, lam, weight_f, weight_g],
                              [ca.triu(weight_f * gauss_newton)],
                              ["x", "p", "lam_f", "lam_g"], ["triu_hess_gamma_x_x"])
        self.solver = ca.nlpsol("elastica_fit", "ipopt",
                                {"x": x_all, "p": lam, "f": f, "g": g_all},
                                {"hess_lag": hessian, "ipopt.print_level": 0,
                                 "print_time": False, "ipopt.sb": "yes",
                                 "ipopt.max_iter": max_iter, "ipopt.tol": 1e-9})
        self.bounds = {"lbg": np.concatenate(lbg), "ubg": np.concatenate(ubg)}
        self.x = np.concatenate([np.log(c_start / c_ref), *w0])
        # the σ-scaled residuals' sensitivity to q with the collocation
        # equations held (implicit function theorem): J = R_q - R_w G_w⁻¹ G_q
        self._sensitivity = ca.Function("fit_sensitivity", [q, wall], [
            r, ca.jacobian(r, q), ca.jacobian(r, wall), ca.jacobian(eqs, q),
            ca.jacobian(eqs, wall), pred_v])
        self.build_time_s = time.perf_counter() - t0

    def solve(self, lam: float) -> IpoptSolve:
        """Solve at weight λ from the last solution (the start the first time)."""
        t0 = time.perf_counter()
        out = self.solver(x0=self.x, p=lam, **self.bounds)
        elapsed = time.perf_counter() - t0
        stats = self.solver.stats()
        self.x = np.asarray(out["x"]).ravel()
        return IpoptSolve(lam, stats.get("return_status", "?"), bool(stats.get("success", False)),
                          int(stats.get("iter_count", 0)), elapsed)

    @property
    def q(self) -> np.ndarray:
        return self.x[:self.n]

    def linearised(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """At the current solution: σ-scaled residuals r, their Jacobian J in q,
        and the predictions (data order); r(q') ≈ r + J (q' - q)."""
        r, Rq, Rw, Gq, Gw, pred = self._sensitivity(self.q, self.x[self.n:])
        dw = spsolve(sp.csc_matrix(Gw.sparse()), sp.csc_matrix(Gq.sparse()))
        dw = dw.toarray() if sp.issparse(dw) else np.asarray(dw).reshape(-1, self.n)
        J = np.asarray(Rq) - sp.csr_matrix(Rw.sparse()) @ dw
        return np.asarray(r).ravel(), np.asarray(J), np.asarray(pred).ravel()
