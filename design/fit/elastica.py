"""The planar elastica at measured points, and the large-deflection refinement.

Predictions: each load case is solved by the toolkit's collocation method
(:class:`design.solve.beam.collocation.Collocation`) and read at the measured
arc lengths by cubic Hermite interpolation of x, y (slopes cos ψ, sin ψ) and
ψ (slope M / EI) between its nodes; past the load point the finger is
straight.

Refinement: a nonlinear least-squares fit of the knot compliances on the
collocated elastica, solved simultaneously (every load case's collocation
unknowns are NLP unknowns, its collocation equations constraints) by Ipopt
with exact derivatives from CasADi. The transcription is the toolkit's
:class:`~design.solve.beam.collocation.BeamTranscription` with the stiffness
:class:`~design.fit.kernel.KnotCompliance`, whose parameters are the knot
compliances; each case's mesh has an interval edge at every knot (EI has a
kink there) and at every measured point inside the loaded span, so a
prediction is a mesh node's value, not an interpolation. Objective: the
convex fit's, ½ ‖r / σ‖² + ½ λ ‖D c / c_ref‖², with its λ and constraints.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, replace

import casadi as ca
import numpy as np
import scipy.sparse as sp
from scipy.interpolate import CubicHermiteSpline
from scipy.sparse.linalg import spsolve

from design.fit.convex import (PER_DECADE, CompliancePQ, ProfileFit, roughness,
                               select_weight)
from design.fit.data import FingerData
from design.fit.kernel import KnotCompliance
from design.physics.beam import BeamSolution, Finger
from design.solve.beam.collocation import Collocation, legendre_tables, transcription

#: collocation degree of the refinement's transcription (nodal order 2d = 6;
#: intervals are a few mm, so its error is far below any bench's noise)
DEGREE = 3
#: intervals of each case's mesh beyond those its knots and points need
SPARE_INTERVALS = 8


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

    Unknowns: z = c / c_ref at the knots, then for each load case its
    collocation unknowns and the x, y of its mesh edges. Objective
    ½ ‖r / σ‖² + ½ λ ‖D z‖²; constraints: the collocation equations, the
    edges' quadrature, z ≥ 1e-6 (EI finite) and the monotonicity asked for.
    """

    def __init__(self, data: FingerData, length: float, knots: np.ndarray,
                 c_start: np.ndarray, c_ref: float, monotone: str | None,
                 start: list[BeamSolution], max_iter: int = 200):
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
        z = ca.SX.sym("z", self.n)
        lam = ca.SX.sym("lam")
        c = c_ref * z
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
                                      *(points_on(sol, finger0, edges[1:])[q] for q in "xy")]))
            for i, o in enumerate(obs):
                if o.case != k:
                    continue
                e = int(np.argmin(np.abs(edges - min(o.s, load.at))))
                ahead = max(o.s - load.at, 0.0)          # past the load point: straight
                pred[i] = {"x": xs[e] + ahead * ca.cos(psis[e]),
                           "y": ys[e] + ahead * ca.sin(psis[e]), "psi": psis[e]}[o.quantity]
        pred_v = ca.vertcat(*pred)
        r = (pred_v - data.values) / data.sigmas
        D = ca.DM(roughness(self.n))
        f = 0.5 * ca.sumsqr(r) + 0.5 * lam * ca.sumsqr(ca.mtimes(D, z))
        wall = ca.vertcat(*ws)
        eqs = ca.vertcat(*G)
        g, lbg, ubg = [eqs], [np.zeros(eqs.shape[0])], [np.zeros(eqs.shape[0])]
        if monotone in ("decreasing", "increasing"):
            g.append(z[1:] - z[:-1])
            lo, hi = (0.0, np.inf) if monotone == "decreasing" else (-np.inf, 0.0)
            lbg.append(np.full(self.n - 1, lo))
            ubg.append(np.full(self.n - 1, hi))
        x_all = ca.vertcat(z, wall)
        self.unknowns = int(x_all.shape[0])
        self.solver = ca.nlpsol("elastica_fit", "ipopt",
                                {"x": x_all, "p": lam, "f": f, "g": ca.vertcat(*g)},
                                {"ipopt.print_level": 0, "print_time": False, "ipopt.sb": "yes",
                                 "ipopt.max_iter": max_iter, "ipopt.tol": 1e-9})
        self.bounds = {"lbx": np.concatenate([np.full(self.n, 1e-6),
                                              np.full(wall.shape[0], -np.inf)]),
                       "ubx": np.full(self.unknowns, np.inf),
                       "lbg": np.concatenate(lbg), "ubg": np.concatenate(ubg)}
        self.x = np.concatenate([np.clip(c_start / c_ref, 0.1, 10.0), *w0])
        # the σ-scaled residuals' sensitivity to z with the collocation
        # equations held (implicit function theorem): J = R_z - R_w G_w⁻¹ G_z
        self._sensitivity = ca.Function("fit_sensitivity", [z, wall], [
            r, ca.jacobian(r, z), ca.jacobian(r, wall), ca.jacobian(eqs, z),
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
    def z(self) -> np.ndarray:
        return self.x[:self.n]

    def linearised(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """At the current solution: σ-scaled residuals r, their Jacobian J in z,
        and the predictions (data order); r(z') ≈ r + J (z' - z)."""
        r, Rz, Rw, Gz, Gw, pred = self._sensitivity(self.z, self.x[self.n:])
        dw = spsolve(sp.csc_matrix(Gw.sparse()), sp.csc_matrix(Gz.sparse()))
        dw = dw.toarray() if sp.issparse(dw) else np.asarray(dw).reshape(-1, self.n)
        J = np.asarray(Rz) - sp.csr_matrix(Rw.sparse()) @ dw
        return np.asarray(r).ravel(), np.asarray(J), np.asarray(pred).ravel()


@dataclass
class Refinement:
    """The elastica fit and how it went: every Ipopt solve (one per weight
    tried), the NLP's size and build time."""

    fit: ProfileFit
    solves: list[IpoptSolve]
    unknowns: int
    build_time_s: float

    @property
    def success(self) -> bool:
        return bool(self.solves) and self.solves[-1].success


#: at most this many weight updates (Ipopt solves) in the refinement
MAX_WEIGHT_UPDATES = 4


def refine(data: FingerData, length: float, start_fit: ProfileFit, monotone: str | None,
           start: list[BeamSolution], rule: str = "gcv") -> Refinement:
    """Nonlinear least squares of the knot compliances on the collocated
    elastica, from the convex fit ``start_fit`` and the elastica solutions
    ``start`` of its profile (one per load case).

    The weight is chosen by the convex fit's rule on the problem linearised
    at the refined solution (Gauss-Newton: r(z) ≈ r* + J (z - z*), the same
    QP with A = J), and the refinement repeated from its last solution until
    the rule picks the weight it was solved at (at most
    :data:`MAX_WEIGHT_UPDATES` times): the convex fit's weight suits the
    linear model's misfit, not the elastica's.
    """
    problem = ElasticaFitProblem(data, length, start_fit.knots, start_fit.c, start_fit.c_ref,
                                 monotone, start)
    lam, solves, sel = start_fit.lam, [], None
    for _ in range(MAX_WEIGHT_UPDATES):
        solves.append(problem.solve(lam))
        r, J, pred = problem.linearised()
        sel = select_weight(J, J @ problem.z - r, monotone, rule)
        # the grid moves with J: the same weight is one within a grid step
        if not solves[-1].success or abs(np.log10(sel.chosen.lam / lam)) < 0.5 / PER_DECADE:
            break
        lam = sel.chosen.lam
    c_ref = start_fit.c_ref
    # the fit's statistics at the weight it was solved at and its own solution
    chosen = replace(sel, chosen=CompliancePQ(J, J @ problem.z - r, monotone).analyse(
        solves[-1].lam, problem.z))
    fit = ProfileFit("elastica", start_fit.knots, problem.z * c_ref,
                     chosen.z_sd() * c_ref, c_ref, chosen,
                     list(range(len(data.observations))), pred)
    return Refinement(fit, solves, problem.unknowns, problem.build_time_s)
