"""CasADi functions of a collocation sweep: continuation runs and their checks.

A sweep (many loads of one direction and position) is solved by
:class:`SweepFunctions` of one transcription: continuation runs inside
CasADi, each load started from the previous solutions and finished by
Newton steps, then the shape (or load point) and the residual of every
load in one mapped call. Large sweeps on meshes no finer than the default
run them compiled (design/solvers/compiled.py, :func:`worth_compiling`), with
condensed Newton steps (:attr:`BeamTranscription.newton_step`); others run
interpreted, with a sparse QR factorisation of the whole Jacobian instead,
which CasADi's virtual machine runs faster than the condensed step's many
scalar operations; compiled, the condensed step is the fastest
(``python -m benchmarks.beam_sweep``).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import casadi as ca
import numpy as np

from design.solvers.compiled import compiled, compiler

if TYPE_CHECKING:
    from design.solvers.beam.collocation import BeamTranscription

#: Newton steps a chained solve takes at most (a rootfinder's default; a
#: dense sweep needs one, a coarse one a few)
MAX_STEPS = 50
#: sweeps of at least this many loads use compiled functions: building them
#: takes seconds (once per machine: the libraries are cached), a smaller
#: sweep milliseconds interpreted
COMPILE_MIN_LOADS = 100
#: ... on meshes of at most this many unknowns (16 intervals of degree 4, the
#: default): the compiler's time grows faster than the mesh, and on a
#: finer one it saves a fraction of a second per 1000 loads
#: (``python -m benchmarks.beam``)
COMPILE_MAX_UNKNOWNS = 160


def worth_compiling(tr: BeamTranscription, loads: int) -> bool:
    """Whether a sweep of ``loads`` loads on ``tr``'s mesh runs compiled."""
    return loads >= COMPILE_MIN_LOADS and tr.n_w <= COMPILE_MAX_UNKNOWNS


class SweepFunctions:
    """One transcription's sweep functions at a Newton tolerance, compiled or not.

    ``step``: (acc, P) -> (acc', [w; steps]), one solve of a continuation run;
    acc = [w1; w2; w3; F1; F2; F3] holds the run's last three solutions and
    their forces (:meth:`start`: a run's first), the start is their quadratic
    extrapolation in F (linear, or the last solution, while the run has
    fewer distinct forces): one Newton step on a 1000-load sweep where the
    secant predictor took two for half the loads at 60°. Plain
    Newton steps (no line search; condensed when compiled, by sparse QR
    otherwise) follow until max |G| ≤ ``tolerance`` or :data:`MAX_STEPS` of
    them: the start is close, and a solve that fails anyway is redone by the
    caller. ``shape_check``, ``tip_check``: the transcription's.
    """

    def __init__(self, tr: BeamTranscription, tolerance: float, compile: bool):
        self.tr, self.tolerance = tr, tolerance
        nw = tr.n_w
        acc = ca.MX.sym("acc", 3 * nw + 3)
        P = ca.MX.sym("P", tr.n_p)
        w = [acc[i * nw:(i + 1) * nw] for i in range(3)]
        f = [acc[3 * nw + i] for i in range(3)]
        weights = extrapolation(P[0], *f)
        compile = compile and compiler()[0] is not None
        newton = self._newton(tr.newton_step if compile else sparse_newton_step(tr), MAX_STEPS)
        solved = newton(sum(a * wi for a, wi in zip(weights, w)), P)
        step = ca.Function("beam_continuation_step", [acc, P],
                           [ca.vertcat(solved[:nw], w[0], w[1], P[0], f[0], f[1]), solved])
        functions = [step, tr.shape_check, tr.tip_check]
        self.step, self.shape_check, self.tip_check = \
            compiled(functions).functions if compile else functions
        self._cache: dict[tuple, ca.Function] = {}

    @staticmethod
    def start(w: np.ndarray, force: float) -> np.ndarray:
        """acc of a run that starts from ``w`` at ``force``."""
        return np.concatenate([w, w, w, [force] * 3])

    def _newton(self, step: ca.Function, steps: int) -> ca.Function:
        """(w, P) -> [w; steps taken] after Newton ``step``s from w, at least
        one, until max |G| ≤ the tolerance or ``steps`` of them. Each further
        step is a branch of a switch on the iterate, evaluated only when
        needed (an MX ``if_else`` would make its branches functions of the
        run's inputs and compute every earlier step again)."""
        tr = self.tr
        w, P = ca.MX.sym("w", tr.n_w), ca.MX.sym("P", tr.n_p)
        after = step(w, P)
        if steps > 1:
            done = ca.Function("beam_newton_done", [w, P], [ca.vertcat(w, 1)])
            more = ca.Function("beam_newton_more", [w, P],
                               [self._newton(step, steps - 1)(w, P)
                                + ca.vertcat(ca.MX(tr.n_w, 1), 1)])
            branch = ca.Function.if_else(f"beam_newton_{steps}", more, done)
            return ca.Function(f"beam_newton_from_{steps}", [w, P],
                               [branch(tr.residual_norm(after, P) > self.tolerance, after, P)])
        return ca.Function("beam_newton_from_1", [w, P], [ca.vertcat(after, 1)])

    def chain(self, n: int, parts: int = 1) -> ca.Function:
        """``parts`` continuation runs of n solves each, in parallel threads:
        (A0[3 n_w + 3 x parts], P[n_p x n parts]) -> (acc, S[n_w + 1 x n parts]),
        S holding each solve's unknowns and the Newton steps it took; A0 holds
        each run's :meth:`start`."""
        key = ("chain", n, parts)
        if key not in self._cache:
            run = self.step.mapaccum("beam_run", n, [0], [0])
            self._cache[key] = run.map(parts, "thread", parts) if parts > 1 else run
        return self._cache[key]

    def mapped(self, name: str, n: int) -> ca.Function:
        """``shape_check`` or ``tip_check`` over n columns at once."""
        key = (name, n)
        if key not in self._cache:
            self._cache[key] = getattr(self, name).map(n)
        return self._cache[key]


def extrapolation(force: ca.MX, f1: ca.MX, f2: ca.MX, f3: ca.MX) -> tuple[ca.MX, ca.MX, ca.MX]:
    """Weights of the last three solutions (at forces f1, f2, f3) that
    extrapolate them to ``force``: quadratic (Lagrange) when the three
    forces differ, linear in the last two when those differ, else the last."""
    quadratic = ca.logic_and(ca.logic_and(f1 != f2, f2 != f3), f1 != f3)
    linear = f1 != f2
    lagrange = [(force - fb) * (force - fc) / ((fa - fb) * (fa - fc))
                for fa, fb, fc in ((f1, f2, f3), (f2, f1, f3), (f3, f1, f2))]
    secant = [(force - f2) / (f1 - f2), (force - f1) / (f2 - f1)]
    return (ca.if_else(quadratic, lagrange[0], ca.if_else(linear, secant[0], 1)),
            ca.if_else(quadratic, lagrange[1], ca.if_else(linear, secant[1], 0)),
            ca.if_else(quadratic, lagrange[2], 0))


def sparse_newton_step(tr: BeamTranscription) -> ca.Function:
    """(w, P) -> w after one Newton step, by a sparse QR factorisation of
    the residual's whole Jacobian: the same step as the condensed one (to
    rounding, tests/test_beam_sweep.py), faster interpreted."""
    w, P = ca.SX.sym("w", tr.n_w), ca.SX.sym("P", tr.n_p)
    G = tr.residual(w, P)
    jacobian = ca.Function("beam_residual_jacobian", [w, P], [ca.jacobian(G, w), G])
    w, P = ca.MX.sym("w", tr.n_w), ca.MX.sym("P", tr.n_p)
    J, G = jacobian(w, P)
    return ca.Function("beam_sparse_newton_step", [w, P], [w - ca.solve(J, G, "qr")])
