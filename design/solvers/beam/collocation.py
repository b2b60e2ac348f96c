"""Legendre-Gauss collocation of the elastica BVP in CasADi.

The transcription (:class:`BeamTranscription`) is the piece the contact
solver and the optimiser reuse: it turns the non-dimensional BVP on
u = s/L in [0, 1],

    ψ' = μ EI_r / EI(uL),   μ' = -κ sin(ψ + α),   κ = F L^2 / EI_r,
    ψ(0) = 0,   μ(1) = 0,          (μ = M L / EI_r, EI_r a reference rigidity)

into residual equations G(w; F, α, L, EI_r, p) = 0 on K intervals of degree d
(Gauss-Legendre points: the interval-end values converge at order 2d), with
x/L = ∫cos ψ du, y/L = ∫sin ψ du by the same quadrature. Everything is a CasADi
SX expression of the load (F, α, L) and the stiffness parameters p, so the
same equations become constraints of a larger NLP, or a CasADi rootfinder
(Newton with line search, exact Jacobian) that is itself differentiable.

References
----------
Thesis §2.2, eq. (2.14)-(2.16). Collocation tables as in CasADi's
``direct_collocation`` example.
"""

from __future__ import annotations

import os
from dataclasses import replace
from functools import lru_cache
from typing import Sequence

import casadi as ca
import numpy as np

from design.physics.beam import (BeamSolution, Finger, PointLoad, classify_branch,
                                 normalise_angle)
from design.physics.stiffness import Stiffness, UniformEI
from design.solvers.beam.base import IterativeMethod, continuation_order, resample, richardson
from design.solvers.beam.condensed import Interval, condensed_step
from design.solvers.beam.frisch_fay import FrischFay, reverse_branch_exists
from design.solvers.beam.sweep import SweepFunctions, worth_compiling
from design.solvers.buffers import evaluate


@lru_cache(maxsize=None)
def legendre_tables(d: int) -> tuple[np.ndarray, ...]:
    """Collocation tables for degree d.

    Returns tau (d+1 points, 0 first), C (derivative: C[r, k] = ℓ_r'(τ_k)),
    D (end values ℓ_r(1)), B (quadrature weights of the d collocation points
    over [0, 1]) and A (A[k, r] = ∫_0^τ_k of the Lagrange basis on the
    collocation points, for interior integrals).
    """
    tau = np.append(0.0, ca.collocation_points(d, "legendre"))
    C = np.zeros((d + 1, d + 1))
    D = np.zeros(d + 1)
    for j in range(d + 1):
        poly = np.poly1d([1.0])
        for r in range(d + 1):
            if r != j:
                poly *= np.poly1d([1.0, -tau[r]]) / (tau[j] - tau[r])
        D[j] = poly(1.0)
        dp = np.polyder(poly)
        C[j] = [dp(t) for t in tau]
    pts = tau[1:]
    A = np.zeros((d, d))
    B = np.zeros(d)
    for j in range(d):
        poly = np.poly1d([1.0])
        for r in range(d):
            if r != j:
                poly *= np.poly1d([1.0, -pts[r]]) / (pts[j] - pts[r])
        ip = np.polyint(poly)
        B[j] = ip(1.0)
        A[:, j] = [ip(t) for t in pts]
    return tau, C, D, B, A


class BeamTranscription:
    """Collocation equations of one finger's elastica (CasADi SX).

    Parameters
    ----------
    stiffness : Stiffness
        Supplies the structure of EI(s); its numeric parameters are inputs.
    intervals, degree : int
        K mesh intervals and polynomial degree d. The interval widths are
        inputs too (they sum to 1 in u), so one compiled transcription serves
        every mesh grading.

    Attributes
    ----------
    n_w : int
        Number of unknowns, 2 K (d+1): (ψ, μ) at each interval start and
        collocation point, interval by interval.
    n_p : int
        Length of the parameter vector P = [F, α, L, EI_r, h_1..h_K, p...].

    A *segment* (``segment=True``) is the part of a finger from arc length s0
    to s0 + L, clamped in its own frame at its start, under a force given by
    its components (F_x, F_y) (N, in that frame) and a point moment at its end:
    P = [F_x, F_y, L, EI_r, h_1..h_K, p..., s0, μ_end], μ(1) = μ_end = M L /
    EI_r. Two segments make a finger loaded at two points
    (design/solvers/contact/planar_belt_equations.py).
    """

    def __init__(self, stiffness: Stiffness, intervals: int, degree: int = 4,
                 segment: bool = False):
        self.K, self.d = int(intervals), int(degree)
        tau, C, D, B, A = legendre_tables(self.d)
        K, d = self.K, self.d
        self.tau = tau
        self.n_w = 2 * K * (d + 1)
        n_stiff = stiffness.params.size
        self.n_p = 4 + K + n_stiff + (2 if segment else 0)
        w = ca.SX.sym("w", self.n_w)
        P = ca.SX.sym("P", self.n_p)
        F, alpha, L, ei_r = P[0], P[1], P[2], P[3]
        widths = P[4:4 + K]
        ps = P[4 + K:4 + K + n_stiff]
        Z = ca.reshape(w, 2, K * (d + 1))
        if segment:
            # the force's components F, alpha -> κ_x, κ_y: μ' = κ_x sin ψ - κ_y cos ψ
            start, mu_end = P[4 + K + n_stiff], P[5 + K + n_stiff]
            kx, ky = F * L ** 2 / ei_r, alpha * L ** 2 / ei_r
            kappa = ca.sqrt(1 + kx ** 2 + ky ** 2) - 1     # the scale 1 + κ, smooth at κ = 0

            def moment_rate(psi):
                return kx * ca.sin(psi) - ky * ca.cos(psi)

            def moment_rate_psi(psi):
                return kx * ca.cos(psi) + ky * ca.sin(psi)
        else:
            start, mu_end = 0.0, None
            kappa = F * L ** 2 / ei_r

            def moment_rate(psi):
                return -kappa * ca.sin(psi + alpha)

            def moment_rate_psi(psi):
                return -kappa * ca.cos(psi + alpha)
        res = []
        u_nodes, psi_nodes, mu_nodes, x_nodes, y_nodes = [], [], [], [], []
        u0 = x0 = y0 = 0
        intervals = []
        for j in range(K):
            h = widths[j]
            cols = [Z[:, j * (d + 1) + r] for r in range(d + 1)]
            if j == 0:
                res.append(cols[0][0])                            # ψ(0) = 0
            cos_c, sin_c, e, q, defects = [], [], [], [], []
            for k in range(1, d + 1):
                u = u0 + tau[k] * h
                zp = sum(C[r, k] * cols[r] for r in range(d + 1))
                e_ratio = ei_r / stiffness.ei_casadi(L * u if mu_end is None else start + L * u,
                                                     ps)
                f = ca.vertcat(cols[k][1] * e_ratio, moment_rate(cols[k][0]))
                res.append((zp / h - f) / (1 + kappa))   # O(1) scale: tolerances are relative
                cos_c.append(ca.cos(cols[k][0]))
                sin_c.append(ca.sin(cols[k][0]))
                e.append(e_ratio)
                q.append(moment_rate_psi(cols[k][0]))
                defects.append(zp / h - f)
            intervals.append(Interval(h, ca.horzcat(*cols), ca.vertcat(*e), ca.vertcat(*q),
                                      ca.horzcat(*defects)))
            end = sum(D[r] * cols[r] for r in range(d + 1))
            if j < K - 1:
                res.append(Z[:, (j + 1) * (d + 1)] - end)          # continuity
            else:
                res.append(end[1] if mu_end is None else end[1] - mu_end)  # μ(1) = μ_end
            # nodes of this interval: its start, then its collocation points
            u_nodes.append(u0)
            psi_nodes.append(cols[0][0])
            mu_nodes.append(cols[0][1])
            x_nodes.append(x0)
            y_nodes.append(y0)
            for k in range(d):
                u_nodes.append(u0 + tau[k + 1] * h)
                psi_nodes.append(cols[k + 1][0])
                mu_nodes.append(cols[k + 1][1])
                x_nodes.append(x0 + h * sum(A[k, r] * cos_c[r] for r in range(d)))
                y_nodes.append(y0 + h * sum(A[k, r] * sin_c[r] for r in range(d)))
            x0 = x0 + h * sum(B[r] * cos_c[r] for r in range(d))
            y0 = y0 + h * sum(B[r] * sin_c[r] for r in range(d))
            u0 = u0 + h
        u_nodes.append(u0)
        psi_nodes.append(end[0])
        mu_nodes.append(end[1])
        x_nodes.append(x0)
        y_nodes.append(y0)
        #: the residual G(w, P)
        name = "beam_segment" if segment else "beam"
        self.residual = ca.Function(f"{name}_residual", [w, P], [ca.vertcat(*res)], ["w", "P"], ["G"])
        #: (w, P) -> s, x, y, ψ, M at the nodes (SI)
        self.shape = ca.Function(
            f"{name}_shape", [w, P],
            [L * ca.vertcat(*u_nodes), L * ca.vertcat(*x_nodes), L * ca.vertcat(*y_nodes),
             ca.vertcat(*psi_nodes), ei_r / L * ca.vertcat(*mu_nodes)],
            ["w", "P"], ["s", "x", "y", "psi", "M"])
        #: (w, P) -> load point (x, y, ψ) in m, m, rad
        self.tip = ca.Function(f"{name}_tip", [w, P],
                               [ca.vertcat(L * x0, L * y0, psi_nodes[-1])], ["w", "P"], ["tip"])
        # checks after a solve, sharing subexpressions with the residual:
        # max |G| with the shape (fine solves) or with the tip (coarse solves)
        g_max = ca.mmax(ca.fabs(ca.vertcat(*res)))
        self.shape_check = ca.Function(f"{name}_shape_check", [w, P],
                                       [*self.shape(w, P), g_max])
        self.tip_check = ca.Function(f"{name}_tip_check", [w, P], [self.tip(w, P), g_max])
        #: (w, P) -> max |G|, and w after one Newton step (design/solvers/beam/condensed.py)
        self.residual_norm = ca.Function(f"{name}_residual_norm", [w, P], [g_max])
        self.newton_step = ca.Function(f"{name}_newton_step", [w, P],
                                       [w + condensed_step(intervals, C, D)])
        self._cache: dict[tuple, object] = {}

    def unknown_nodes(self, widths: np.ndarray) -> np.ndarray:
        """u of each (ψ, μ) pair in w, for the given interval widths."""
        starts = np.concatenate([[0.0], np.cumsum(widths)[:-1]])
        return (starts[:, None] + self.tau[None, :] * widths[:, None]).ravel()

    def parameters(self, load: PointLoad, stiffness: Stiffness, ei_ref: float,
                   widths: np.ndarray) -> np.ndarray:
        """Numeric P = [F, α, L, EI_r, h..., p...]."""
        return np.concatenate([[load.force, load.alpha, load.at, ei_ref], widths,
                               stiffness.params])

    def guess(self, sol: BeamSolution, ei_ref: float, widths: np.ndarray) -> np.ndarray:
        """Unknown vector w interpolated from any solution of the same load."""
        psi, m = resample(sol, self.unknown_nodes(widths))
        return np.stack([psi, m * sol.load.at / ei_ref], 1).ravel()

    def rootfinder(self, tolerance: float = 1e-13, max_iter: int = 50,
                   line_search: bool = True) -> ca.Function:
        """CasADi Newton rootfinder (w0, P) -> w, differentiable in P (cached).

        Dense QR for the Newton steps: faster than CSparse at these sizes
        (a few hundred unknowns, ``python -m benchmarks.beam``).
        """
        key = (tolerance, max_iter, line_search)
        if key not in self._cache:
            self._cache[key] = ca.rootfinder(
                "beam_newton", "newton", self.residual,
                {"abstol": tolerance, "max_iter": max_iter, "error_on_fail": False,
                 "line_search": line_search, "linear_solver": "qr",
                 "show_eval_warnings": False})
        return self._cache[key]

    def sweep(self, tolerance: float, compile: bool) -> SweepFunctions:
        """The functions a sweep evaluates (design/solvers/beam/sweep.py; cached)."""
        key = ("sweep", tolerance, compile)
        if key not in self._cache:
            self._cache[key] = SweepFunctions(self, tolerance, compile)
        return self._cache[key]


def adapted_widths(intervals: int, stiffness: Stiffness, guesses: Sequence[BeamSolution],
                   samples: int = 400) -> np.ndarray:
    """Interval widths (in u, summing to 1) that equidistribute a monitor.

    m(u) = 1 + (|(ln EI)'| + |(ln EI)''|^(1/2) + |ψ'|) / 2, derivatives in u,
    ψ from the guesses (the largest over them, so that one mesh serves a
    sweep): intervals shrink where the stiffness changes fast (the
    thesis finger's base) and where the finger bends sharply (the boundary
    layer of width ~1/(kL) under heavy loads). The weights were chosen by
    measurement over uniform and non-uniform fingers, moderate and extreme
    loads (5-100x smaller error than a uniform mesh at K = 16, never worse
    than 2x).
    """
    L = guesses[0].load.at
    u = np.linspace(0.0, 1.0, samples + 1)
    s = u * L
    ei = stiffness.ei(s)
    d1 = np.gradient(np.log(ei), u)
    d2 = np.gradient(d1, u)
    dpsi = np.max([np.abs(resample(g, u)[1]) for g in guesses], axis=0) / ei * L
    monitor = 1.0 + 0.5 * (np.abs(d1) + np.sqrt(np.abs(d2)) + dpsi)
    cum = np.concatenate([[0.0], np.cumsum((monitor[1:] + monitor[:-1]) / 2 * np.diff(u))])
    edges = np.interp(np.linspace(0.0, cum[-1], intervals + 1), cum, u)
    edges[0], edges[-1] = 0.0, 1.0
    return np.diff(edges)


_TRANSCRIPTIONS: dict[tuple, BeamTranscription] = {}


def transcription(stiffness: Stiffness, intervals: int, degree: int = 4,
                  segment: bool = False) -> BeamTranscription:
    """Shared :class:`BeamTranscription` for this stiffness structure and mesh.

    Building one costs far more than a solve; fingers that differ only in their
    parameters (E, EI, the exponential's coefficients) share it.
    """
    key = (stiffness.symbolic_key(), int(intervals), int(degree), bool(segment))
    if key not in _TRANSCRIPTIONS:
        _TRANSCRIPTIONS[key] = BeamTranscription(stiffness, intervals, degree, segment)
    return _TRANSCRIPTIONS[key]


class Collocation(IterativeMethod):
    """CasADi Gauss-Legendre collocation; ``nodes`` = K intervals (degree 4 by default)."""

    name = "collocation"
    default_nodes = 16
    degree = 4

    def __init__(self, finger, nodes=None, tolerance=None, degree: int | None = None):
        super().__init__(finger, nodes, tolerance)
        if degree is not None:
            self.degree = int(degree)
        # nodal order is 2d, but fast-varying EI keeps meshes pre-asymptotic
        # (below 2d at the default mesh on the thesis finger): error estimates
        # use the stage order d, which over-estimates by ≤ 2^d when asymptotic
        self.order = self.degree
        stiff = finger.stiffness
        self._fine = transcription(stiff, self.nodes, self.degree)
        self._coarse = transcription(stiff, max(self.nodes // 2, 1), self.degree)
        self._rf_fine = self._fine.rootfinder(self.tolerance)
        self._rf_coarse = self._coarse.rootfinder(self.tolerance)

    def solve(self, loads: Sequence[PointLoad]) -> list[BeamSolution]:
        """Sweeps run as CasADi continuation chains (one call per run of loads
        with the same direction and position); loads a chain does not solve
        on the continued branch fall back to :meth:`solve_one`."""
        loads = list(loads)
        out: list[BeamSolution | None] = [None] * len(loads)
        for group in _chainable_runs(loads):
            sols = self._batch([loads[i] for i in group]) if len(group) >= BATCH_MIN \
                else [None] * len(group)
            for i, sol in zip(group, sols):
                out[i] = sol
        for i, load in enumerate(loads):
            if out[i] is None:
                out[i] = self.solve_one(load)
        return out  # type: ignore[return-value]

    def _batch(self, loads: list[PointLoad]) -> list[BeamSolution | None]:
        """A sweep as continuation chains (fine, and coarse for the estimate);
        None where a load must be redone one by one."""
        stiff = self.finger.stiffness
        n = len(loads)
        at, alpha = loads[0].at, loads[0].alpha
        ei_ref = stiff.compliance_equivalent(at)
        parts = max(1, min(os.cpu_count() or 1, n // MIN_RUN))
        starts = [j * -(-n // parts) for j in range(parts)]
        # seeds: each run's start, and the largest load (it sets the mesh: it bends most)
        seeds = FrischFay(Finger(self.finger.length, UniformEI(ei_ref)), nodes=201).solve(
            [loads[j] for j in starts] + [loads[-1]])
        widths = adapted_widths(self.nodes, stiff, [seeds[0], seeds[-1]])
        forces = np.array([ld.force for ld in loads])
        fine, coarse = (tr.sweep(self.tolerance, worth_compiling(self._fine, n))
                        for tr in (self._fine, self._coarse))
        W, steps, P = self._chain(fine, forces, alpha, at, seeds[:-1], starts, widths, ei_ref)
        *shape, g_fine = evaluate(fine.mapped("shape_check", n), W, P)
        W, _, P = self._chain(coarse, forces, alpha, at, seeds[:-1], starts,
                              self._coarse_widths(widths, seeds), ei_ref)
        coarse_tips, g_coarse = evaluate(coarse.mapped("tip_check", n), W, P)
        s, x, y, psi, M = shape
        g_fine, g_coarse = g_fine[0], g_coarse[0]
        # the continued branch bends the way the transverse part pushes
        span = np.max(np.abs(psi), axis=0)
        primary = np.all(np.sign(np.sin(alpha)) * psi >= -1e-9 * span, axis=0)
        ok = (g_fine <= CHAIN_RESIDUAL) & primary
        order = stiff.order_cap(self.order)
        est = richardson((x[-1], y[-1]), coarse_tips[:2], order, self._fine.K / self._coarse.K)
        est = np.where(g_coarse <= CHAIN_RESIDUAL, est, np.inf) + g_fine * at \
            + s.shape[0] * np.finfo(float).eps * at
        flags = reverse_branch_exists(at * np.sqrt(forces / stiff.ei(0.0)), np.full(n, alpha)) \
            if stiff.uniform else [None] * n
        return [BeamSolution(ld, self.name, s[:, j], x[:, j], y[:, j], psi[:, j], M[:, j],
                             error_estimate=float(est[j]), converged=True, branch="primary",
                             iterations=int(steps[j]),
                             multiple_equilibria=None if flags[j] is None else bool(flags[j]),
                             extras={"K": self._fine.K, "degree": self.degree, "widths": widths,
                                     "max_residual": float(g_fine[j])})
                if ok[j] else None for j, ld in enumerate(loads)]

    def _chain(self, sweep: SweepFunctions, forces: np.ndarray, alpha: float, at: float,
               seeds: list[BeamSolution], starts: list[int], widths: np.ndarray,
               ei_ref: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Solve a sweep as len(starts) parallel runs; returns unknowns, Newton
        steps and parameters (n_w x n, n and n_p x n)."""
        tr = sweep.tr
        n, parts = forces.size, len(starts)
        per = -(-n // parts)
        padded = np.concatenate([forces, np.full(per * parts - n, forces[-1])])
        P = np.empty((tr.n_p, padded.size))
        P[0], P[1], P[2], P[3] = padded, alpha, at, ei_ref
        P[4:4 + tr.K] = widths[:, None]
        P[4 + tr.K:] = self.finger.stiffness.params[:, None]
        A0 = np.stack([sweep.start(tr.guess(sd, ei_ref, widths), padded[j])
                       for sd, j in zip(seeds, starts)], 1)
        S = evaluate(sweep.chain(per, parts), A0, P)[1]
        return S[:-1, :n], S[-1, :n], P[:, :n]

    def _coarse_widths(self, widths: np.ndarray, guesses: Sequence[BeamSolution]) -> np.ndarray:
        """Pairs of fine intervals merged: the same mesh map at half K (ratio exactly 2)."""
        if self.nodes % 2 == 0:
            return widths[0::2] + widths[1::2]
        return adapted_widths(self._coarse.K, self.finger.stiffness, guesses)

    def _discrete(self, load: PointLoad, guess: BeamSolution, coarse: bool) -> BeamSolution:
        if not coarse:
            widths = adapted_widths(self.nodes, self.finger.stiffness, [guess])
            return self._run(self._fine, self._rf_fine, load, guess, widths)
        widths = self._coarse_widths(guess.extras["widths"], [guess])
        return self._run(self._coarse, self._rf_coarse, load, guess, widths)

    def _resolution(self, sol: BeamSolution) -> float:
        return sol.extras["K"]

    def _solve_error(self, sol: BeamSolution) -> float:
        # an unconverged residual r (normalised, relative) moves the tip by ~ r L
        return sol.extras["max_residual"] * sol.load.at

    def _run(self, tr: BeamTranscription, rf: ca.Function, load: PointLoad,
             guess: BeamSolution, widths: np.ndarray) -> BeamSolution:
        ei_ref = self.finger.stiffness.compliance_equivalent(load.at)
        P = tr.parameters(load, self.finger.stiffness, ei_ref, widths)
        w = rf(tr.guess(guess, ei_ref, widths), P)
        stats = rf.stats()
        *shape, G = (np.asarray(v).ravel() for v in tr.shape_check(w, P))
        ok = bool(stats.get("success", False)) and np.isfinite(G[0])
        sol = self._solution(tr, load, shape, float(G[0]), ok, int(stats.get("iter_count", 0)),
                             widths)
        return sol if ok else replace(sol, message=f"Newton: {stats.get('return_status', 'failed')}")

    def _solution(self, tr: BeamTranscription, load: PointLoad, shape: list[np.ndarray],
                  residual: float, ok: bool, iterations: int, widths: np.ndarray) -> BeamSolution:
        s, x, y, psi, M = shape
        return BeamSolution(load, self.name, s, x, y, psi, M, error_estimate=np.inf,
                            converged=bool(ok), branch=classify_branch(load.alpha, psi),
                            iterations=iterations,
                            extras={"K": tr.K, "degree": tr.d, "widths": widths,
                                    "max_residual": residual})


#: a sweep is solved as a chain when it has at least this many loads
BATCH_MIN = 4
#: loads per parallel run, at least (a run's first solve starts from a seed)
MIN_RUN = 64
#: normalised residual below which a chained solve counts as converged
CHAIN_RESIDUAL = 1e-10


def _chainable_runs(loads: list[PointLoad]) -> list[list[int]]:
    """Runs of load indices, in continuation order, that share direction and
    position and need no special case (zero or purely axial loads do)."""
    runs: list[list[int]] = []
    key = None
    for i in continuation_order(loads):
        ld = loads[i]
        if ld.force == 0.0 or normalise_angle(ld.alpha) == 0.0:
            continue
        if (ld.alpha, ld.at) != key:
            runs.append([])
            key = (ld.alpha, ld.at)
        runs[-1].append(i)
    return runs
