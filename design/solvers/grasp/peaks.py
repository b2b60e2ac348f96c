"""Finger-force maxima between the integrator's accepted instants.

A finger's force is known at the accepted instants only, so its peak, read
there, is low by up to half a step's worth of its curvature
(tests/test_peaks.py compares located peaks with a much finer run). Where
a finger's force at an accepted instant exceeds its neighbours', its
maximum lies between them: it is found by successive parabolic
interpolation on the steps' dense output, each
trial a contact evaluation from the contacts accepted before the step that
covers it (what the step's own stages continued from). The integration
itself is left exactly as it was.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass
from typing import Callable

import numpy as np

#: a maximum is found when an interpolation step raises it by at most this (relative)
PEAK_RTOL = 1e-7
#: interpolation steps per maximum, at most
PEAK_EVALUATIONS = 8


@dataclass(frozen=True)
class Peak:
    """A finger's force maximum found between accepted instants: time (s),
    the bird's state there, the finger's contact."""

    t: float
    y: np.ndarray
    state: object

    @property
    def force(self) -> float:
        return self.state.magnitude


@dataclass(frozen=True)
class Span:
    """One accepted step: from ``t0`` to ``t1`` (s), its dense output, and the
    fingers' snapshot it was integrated from."""

    t0: float
    t1: float
    dense: Callable
    snapshot: tuple


class PeakFinder:
    """Each finger's largest force found between the last three accepted
    instants after each step (``peaks``: finger index -> :class:`Peak`,
    where it exceeds the records'); the instants themselves are the records'."""

    def __init__(self, fingers):
        self.fingers = fingers
        self.spans: deque[Span] = deque(maxlen=2)
        self.peaks: dict[int, Peak] = {}

    def accepted(self, span: Span, records: list) -> None:
        """``span`` ended at the latest record: look for each finger's maximum
        between the three latest records."""
        self.spans.append(span)
        if len(self.spans) < 2 or len(records) < 3:
            return
        a, b, c = records[-3:]
        first, second = self.spans
        if not (first.t0 == a.t and first.t1 == b.t == second.t0 and second.t1 == c.t):
            return
        probed: dict[float, tuple] = {}

        def force(t: float, j: int) -> float:
            if t not in probed:
                span = first if t <= first.t1 else second
                y = span.dense(t)
                probed[t] = y, self.fingers.probe(t, y, span.snapshot)
            return probed[t][1][j].magnitude

        for j, (fa, fb, fc) in enumerate(zip(*([f.magnitude for f in r.fingers]
                                                for r in (a, b, c)))):
            if fb > 0.0 and fb > fa and fb >= fc:
                t, f = interpolated_maximum(lambda t, j=j: force(t, j), a.t, b.t, c.t, fa, fb, fc)
                if f > fb and (j not in self.peaks or f > self.peaks[j].force):
                    self.peaks[j] = Peak(t, probed[t][0], probed[t][1][j])


def interpolated_maximum(f: Callable[[float], float], a: float, b: float, c: float,
                         fa: float, fb: float, fc: float) -> tuple[float, float]:
    """Successive parabolic interpolation for a maximum of f bracketed by
    a < b < c with f(b) ≥ f(a), f(c): (t, f(t)), the largest value found."""
    for _ in range(PEAK_EVALUATIONS):
        p, q = (b - a) * (fb - fc), (b - c) * (fb - fa)
        if p == q:
            break
        x = b - 0.5 * ((b - a) * p - (b - c) * q) / (p - q)
        if not a < x < c or x == b:
            break
        fx = f(x)
        raised = fx - fb
        if fx > fb:
            a, b, c, fa, fb, fc = (a, x, b, fa, fx, fb) if x < b else (b, x, c, fb, fx, fc)
        elif x < b:
            a, fa = x, fx
        else:
            c, fc = x, fx
        if abs(raised) <= PEAK_RTOL * fb:
            break
    return b, fb


def merged_peaks(force: np.ndarray, times: np.ndarray, peaks: dict[int, Peak]
                 ) -> tuple[np.ndarray, np.ndarray]:
    """Each finger's largest force (N) and its time (s): over the records
    (``force`` records x fingers, ``times``) and the maxima found between them."""
    k = np.argmax(force, axis=0)
    best, when = force[k, np.arange(force.shape[1])], times[k]
    for j, p in peaks.items():
        if p.force > best[j]:
            best[j], when[j] = p.force, p.t
    return best, when
