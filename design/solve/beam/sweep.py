"""CasADi functions of a collocation sweep: continuation runs and their checks.

A sweep (many loads of one direction and position) is solved by
:class:`SweepFunctions` of one transcription: continuation runs inside
CasADi, each load started from the previous two solutions and finished by
condensed Newton steps (:attr:`BeamTranscription.newton_step`), then the
shape (or load point) and the residual of every load in one mapped call.
Large sweeps on meshes no finer than the default run them compiled
(design/solve/compiled.py, :func:`worth_compiling`), others interpreted.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import casadi as ca
import numpy as np

from design.solve.compiled import compiled

if TYPE_CHECKING:
    from design.solve.beam.collocation import BeamTranscription

#: Newton steps a chained solve takes at most: from the secant predictor one
#: or two on a 1000-load sweep, three or four on a 13-load one (measured);
#: every step is a level of nested conditionals in the compiled library (50
#: levels took 3.5 s more compiler time than 10)
MAX_STEPS = 10
#: sweeps of at least this many loads use compiled functions: building them
#: takes seconds (once per machine: the libraries are cached), a smaller
#: sweep milliseconds interpreted
COMPILE_MIN_LOADS = 100
#: ... on meshes of at most this many unknowns (16 intervals of degree 4, the
#: default): the compiler's time grows faster than the mesh (fine and coarse
#: library, measured: 8 s at 16 intervals, 38 s at 32), and at 32 intervals
#: it saves 0.4 s per 1000 loads (0.09 s compiled, 0.49 s interpreted)
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
    secant predictor took two for half the loads at 60° (measured). Plain
    Newton steps (no line search) follow until max |G| ≤ ``tolerance`` or
    :data:`MAX_STEPS` of them: the start is close, and a solve that fails
    anyway is redone by the caller. ``shape_check``, ``tip_check``: the
    transcription's.
    """

    def __init__(self, tr: BeamTranscription, tolerance: float, compile: bool):
        self.tr, self.tolerance = tr, tolerance
        nw = tr.n_w
        acc = ca.MX.sym("acc", 3 * nw + 3)
        P = ca.MX.sym("P", tr.n_p)
        w = [acc[i * nw:(i + 1) * nw] for i in range(3)]
        f = [acc[3 * nw + i] for i in range(3)]
        weights = extrapolation(P[0], *f)
        solved = self._newton(sum(a * wi for a, wi in zip(weights, w)), P, MAX_STEPS)
        step = ca.Function("beam_continuation_step", [acc, P],
                           [ca.vertcat(solved[:nw], w[0], w[1], P[0], f[0], f[1]), solved])
        functions = [step, tr.shape_check, tr.tip_check]
        done = compiled(functions) if compile else None
        self.compiled = done is not None and done.compiled
        self.step, self.shape_check, self.tip_check = done.functions if done else functions
        self._cache: dict[tuple, ca.Function] = {}

    @staticmethod
    def start(w: np.ndarray, force: float) -> np.ndarray:
        """acc of a run that starts from ``w`` at ``force``."""
        return np.concatenate([w, w, w, [force] * 3])

    def _newton(self, w: ca.MX, P: ca.MX, steps: int) -> ca.MX:
        """[w; steps taken] after Newton steps from w, at least one, until
        max |G| ≤ the tolerance or ``steps`` of them (each further step is
        evaluated only when needed)."""
        tr = self.tr
        w = tr.newton_step(w, P)
        done = ca.vertcat(w, 1)
        if steps == 1:
            return done
        more = self._newton(w, P, steps - 1) + ca.vertcat(ca.MX(tr.n_w, 1), 1)
        return ca.if_else(tr.residual_norm(w, P) > self.tolerance, more, done, True)

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
