"""What every study produces: rows (one per solver setting), the Pareto
front of error against wall time, and the cheapest setting meeting a tolerance.

Errors are relative to a reference (dimensionless); wall times are in s.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

#: most calls :func:`timed` makes to fill its time budget
MAX_REPEAT = 100


@dataclass
class Row:
    """One solver setting of a level, measured against the level's reference.

    ``errors`` are relative errors (dimensionless) by metric name; ``error``,
    their largest, is what the front and the tolerance use. ``values`` are the
    setting's own results (SI units in their names). A setting that did not
    converge keeps its errors but is neither on the front nor a candidate.
    """

    level: str
    method: str
    label: str
    setting: dict
    errors: dict[str, float]
    wall_time_s: float
    first_run_s: float
    is_default: bool = False
    is_reference: bool = False
    converged: bool = True
    note: str = ""
    values: dict = field(default_factory=dict)
    on_front: bool = False
    meets_tolerance: bool | None = None

    @property
    def error(self) -> float:
        return max(self.errors.values(), default=math.inf)

    @property
    def usable(self) -> bool:
        """Converged, with a finite error: a candidate for the front."""
        return self.converged and math.isfinite(self.error)


@dataclass
class Study:
    """A level's rows and what they were measured against."""

    level: str
    rows: list[Row]
    #: the reference: its setting, what it is, its results
    reference: dict
    #: metric name -> what it measures (relative to the reference)
    metrics: dict[str, str]
    #: the setting the scene itself asks for (None: not among the rows)
    scene_setting: dict | None = None
    notes: list[str] = field(default_factory=list)

    @property
    def default(self) -> Row:
        return next(r for r in self.rows if r.is_default)


def relative(values, reference) -> float:
    """Largest |value - reference| over the largest |reference| (both arrays
    of scalars or of vectors, same shape); 0 for identical arrays, inf when
    the reference is zero and the values are not."""
    values, reference = np.asarray(values, float), np.asarray(reference, float)
    if values.shape != reference.shape:
        return math.inf
    diff = values - reference
    if diff.ndim > 1:
        diff, reference = np.linalg.norm(diff, axis=-1), np.linalg.norm(reference, axis=-1)
    if not np.all(np.isfinite(diff)):
        return math.inf
    worst = float(np.max(np.abs(diff), initial=0.0))
    scale = float(np.max(np.abs(reference), initial=0.0))
    if worst == 0.0:
        return 0.0
    return worst / scale if scale > 0 else math.inf


def timed(fn: Callable[[], object], repeat: int = 1, warmup: bool = False,
          budget: float = 0.0) -> tuple[object, float, float]:
    """Result, best wall time (s) of the calls, and the warm-up's (s; without
    one, the best again).

    At least ``repeat`` calls, more (at most :data:`MAX_REPEAT`) until they
    have taken ``budget`` s, so that the best of cheap calls is not one
    disturbed by other work on the machine. With ``warmup`` a first call is
    made before them, outside the best: it pays one-off construction (CasADi
    functions built and cached), which the repeats then do not.
    """
    first = math.inf
    if warmup:
        t0 = time.perf_counter()
        fn()
        first = time.perf_counter() - t0
    best, out, count, start = math.inf, None, 0, time.perf_counter()
    while count < max(repeat, 1) or (time.perf_counter() - start < budget
                                     and count < MAX_REPEAT):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
        count += 1
    return out, best, first if warmup else best


def dominates(a: Row, b: Row) -> bool:
    """Is a at least as fast and as accurate as b, and strictly better in one?"""
    return (a.wall_time_s <= b.wall_time_s and a.error <= b.error
            and (a.wall_time_s < b.wall_time_s or a.error < b.error))


def mark_front(rows: list[Row]) -> None:
    """Set ``on_front``: usable rows that no other usable row dominates."""
    usable = [r for r in rows if r.usable]
    for r in rows:
        r.on_front = r.usable and not any(dominates(o, r) for o in usable if o is not r)


def choose(rows: list[Row], tolerance: float | None) -> Row | None:
    """Set ``meets_tolerance`` and return the cheapest usable row whose error is
    at most ``tolerance`` (None: no tolerance given, or no row meets it)."""
    if tolerance is None:
        for r in rows:
            r.meets_tolerance = None
        return None
    for r in rows:
        r.meets_tolerance = r.usable and r.error <= tolerance
    meeting = [r for r in rows if r.meets_tolerance]
    return min(meeting, key=lambda r: (r.wall_time_s, r.error)) if meeting else None
