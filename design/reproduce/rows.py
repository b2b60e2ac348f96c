"""One row of the reproduction report: a thesis number or claim against ours.

A numeric row agrees when |ours - thesis| <= tolerance (in the row's unit).
A claim row (the thesis states a trend, a bound or a reading of a plot)
agrees when ours bears the claim out, by the criterion its explanation
states. Every tolerance is fixed before the comparison, from the thesis's
printed digits or its stated accuracy, never from our own results.

Each row names its ``basis``: a number the thesis prints, a statement it
makes (a trend, a bound, a reading of a plot), what its experiment measured
(the football of §5.3: its rise, its attitude on video, its passing), or
one of our own references standing in where the thesis prints nothing (a
closed form, a finer method). Numbers and statements come from the
thesis's own calculations and simulations; measurements do not.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

#: the columns of reproduction.json / .csv and of the report's tables, in order
COLUMNS = ("case", "quantity", "basis", "unit", "thesis", "ours", "difference",
           "relative_difference", "tolerance", "agrees", "explanation")
#: what a row compares ours with
THESIS_NUMBER, THESIS_STATEMENT, THESIS_MEASUREMENT, OWN_REFERENCE = (
    "thesis number", "thesis statement", "thesis measurement", "own reference")
BASES = (THESIS_NUMBER, THESIS_STATEMENT, THESIS_MEASUREMENT, OWN_REFERENCE)


class CaseFailed(RuntimeError):
    """A reference case whose solution did not converge or finish."""


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
    basis: str = THESIS_NUMBER

    @property
    def numeric(self) -> bool:
        return isinstance(self.thesis, float) and isinstance(self.ours, float)

    @property
    def difference(self) -> float | None:
        """ours - thesis, in ``unit``; None for a claim."""
        return self.ours - self.thesis if self.numeric else None

    @property
    def relative_difference(self) -> float | None:
        """(ours - thesis) / |thesis|; None for a claim or a zero thesis value."""
        return self.difference / abs(self.thesis) if self.numeric and self.thesis else None

    @property
    def agrees(self) -> bool:
        if self.numeric:
            return math.isfinite(self.ours) and abs(self.difference) <= self.tolerance
        return bool(self.holds)

    def as_dict(self) -> dict:
        return {c: getattr(self, c) for c in COLUMNS}


def compare(case: str, quantity: str, unit: str, thesis: float, ours: float, tolerance: float,
            explanation: str = "", basis: str = THESIS_NUMBER) -> Row:
    """A numeric row: agrees when |ours - thesis| <= tolerance (``unit``)."""
    return Row(case, quantity, unit, float(thesis), float(ours), explanation, float(tolerance),
               basis=basis)


def claim(case: str, quantity: str, thesis: str, ours: float | str, holds: bool,
          explanation: str, unit: str = "", basis: str = THESIS_STATEMENT) -> Row:
    """A claim row: the thesis's statement, our number or finding, and whether it holds."""
    return Row(case, quantity, unit, thesis, float(ours) if not isinstance(ours, str) else ours,
               explanation, holds=bool(holds), basis=basis)


def tally(rows: list[Row]) -> tuple[int, int]:
    """(rows that agree, rows)."""
    return sum(r.agrees for r in rows), len(rows)


def tally_by_basis(rows: list[Row]) -> dict[str, tuple[int, int]]:
    """Per basis present: (rows that agree, rows)."""
    return {b: tally([r for r in rows if r.basis == b]) for b in BASES
            if any(r.basis == b for r in rows)}


def verdict(rows: list[Row]) -> str:
    """'k of n rows agree ...', split by basis."""
    parts = [f"{b}s: {k} of {n}" for b, (k, n) in tally_by_basis(rows).items()]
    agree, total = tally(rows)
    return (f"{agree} of {total} rows agree within their stated tolerance "
            f"({'; '.join(parts)})")


@dataclass
class Section:
    """A part of the report: its rows, a paragraph and figures (matplotlib
    figure, file name without .png, caption)."""

    anchor: str
    title: str
    text: str
    rows: list[Row]
    figures: list[tuple[object, str, str]] = field(default_factory=list)
