"""One row of the reproduction report: a thesis number or claim against ours.

A numeric row (kind "number") agrees when |ours - thesis| <= tolerance (in
the row's unit). A claim row (kind "statement": a trend, a bound or a
reading of a plot) agrees when ours bears the claim out, by the criterion
its explanation states. Every tolerance is fixed before the comparison,
from the thesis's printed digits or its stated accuracy, never from our
own results.

Each row names its ``basis``, the evidence it is compared with: a thesis
measurement (the football experiment of §5.3: its rise, what its video
shows), a thesis simulation (the thesis's own calculations and
simulations, numbers and statements alike), or an own reference standing
in where the thesis prints nothing (a closed form, a finer method). The
verdict counts each apart. A context row stands a quantity of ours beside
the thesis's where the two are not the same quantity (a substitute), or
shows a reading the thesis leaves open: shown, never counted.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

#: the columns of reproduction.json / .csv and of the report's tables, in order
COLUMNS = ("case", "quantity", "basis", "kind", "unit", "thesis", "ours", "difference",
           "relative_difference", "tolerance", "agrees", "explanation")
#: what a row compares ours with: the evidence levels the verdict counts apart
THESIS_MEASUREMENT, THESIS_SIMULATION, OWN_REFERENCE = (
    "thesis measurement", "thesis simulation", "own reference")
BASES = (THESIS_MEASUREMENT, THESIS_SIMULATION, OWN_REFERENCE)
#: a row shown beside the others and never counted
CONTEXT = "context"


class CaseFailed(RuntimeError):
    """A reference case whose solution did not converge or finish; ``sections``
    holds what could be built without it."""

    def __init__(self, message: str, sections: list | None = None):
        super().__init__(message)
        self.sections = sections or []


@dataclass(frozen=True)
class Row:
    """A compared quantity; ``thesis`` and ``ours`` in ``unit`` (SI) or text."""

    case: str
    quantity: str
    unit: str
    thesis: float | str
    ours: float | str
    explanation: str = ""
    tolerance: float | None = None
    holds: bool | None = None
    basis: str = THESIS_SIMULATION

    @property
    def numeric(self) -> bool:
        return isinstance(self.thesis, float) and isinstance(self.ours, float)

    @property
    def kind(self) -> str:
        """'number' (a numeric row) or 'statement' (a claim)."""
        return "number" if self.numeric else "statement"

    @property
    def counted(self) -> bool:
        """Whether the verdict counts the row (a context row it does not)."""
        return self.basis != CONTEXT

    @property
    def difference(self) -> float | None:
        """ours - thesis, in ``unit``; None for a claim."""
        return self.ours - self.thesis if self.numeric else None

    @property
    def relative_difference(self) -> float | None:
        """(ours - thesis) / |thesis|; None for a claim or a zero thesis value."""
        return self.difference / abs(self.thesis) if self.numeric and self.thesis else None

    @property
    def agrees(self) -> bool | None:
        """Whether ours meets the thesis; None for a context row."""
        if not self.counted:
            return None
        if self.numeric:
            return math.isfinite(self.ours) and abs(self.difference) <= self.tolerance
        return bool(self.holds)

    def as_dict(self) -> dict:
        return {c: getattr(self, c) for c in COLUMNS}


def compare(case: str, quantity: str, unit: str, thesis: float, ours: float, tolerance: float,
            explanation: str = "", basis: str = THESIS_SIMULATION) -> Row:
    """A numeric row: agrees when |ours - thesis| <= tolerance (``unit``)."""
    return Row(case, quantity, unit, float(thesis), float(ours), explanation, float(tolerance),
               basis=basis)


def claim(case: str, quantity: str, thesis: str, ours: float | str, holds: bool,
          explanation: str, unit: str = "", basis: str = THESIS_SIMULATION) -> Row:
    """A claim row: the thesis's statement, our number or finding, and whether it holds."""
    return Row(case, quantity, unit, thesis, float(ours) if not isinstance(ours, str) else ours,
               explanation, holds=bool(holds), basis=basis)


def context(case: str, quantity: str, thesis: float | str, ours: float | str,
            explanation: str, unit: str = "") -> Row:
    """A context row: ours beside the thesis's, shown and never counted."""
    def value(v):
        return v if isinstance(v, str) else float(v)
    return Row(case, quantity, unit, value(thesis), value(ours), explanation, basis=CONTEXT)


def tally(rows: list[Row]) -> tuple[int, int]:
    """(counted rows that agree, counted rows): context rows left out."""
    counted = [r for r in rows if r.counted]
    return sum(bool(r.agrees) for r in counted), len(counted)


def tally_by_basis(rows: list[Row]) -> dict[str, tuple[int, int]]:
    """Per basis present: (rows that agree, rows)."""
    return {b: tally([r for r in rows if r.basis == b]) for b in BASES
            if any(r.basis == b for r in rows)}


def verdict(rows: list[Row]) -> str:
    """'k of n rows agree ...', split by basis, and the context rows not counted."""
    parts = [f"{b}s: {k} of {n}" for b, (k, n) in tally_by_basis(rows).items()]
    agree, total = tally(rows)
    shown = sum(not r.counted for r in rows)
    return (f"{agree} of {total} rows agree within their stated tolerance "
            f"({'; '.join(parts)})" + (f"; {shown} context row{'s' * (shown != 1)} shown, "
                                       "not counted" if shown else ""))


@dataclass
class Section:
    """A part of the report: its rows, a paragraph, figures (matplotlib
    figure, file name without .png, caption) and tables shown beside the
    rows, never counted (id, caption, rows as dicts)."""

    anchor: str
    title: str
    text: str
    rows: list[Row]
    figures: list[tuple[object, str, str]] = field(default_factory=list)
    tables: list[tuple[str, str, list[dict]]] = field(default_factory=list)
