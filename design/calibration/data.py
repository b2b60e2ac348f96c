"""Bench measurements of a finger, as the fits use them (SI)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from design.physics.beam import PointLoad

#: what a measured value is: the point's position along and across the
#: unloaded finger (m) or the finger's slope there (rad)
QUANTITIES = ("x", "y", "psi")


@dataclass(frozen=True)
class Observation:
    """One measured value: of load case ``case`` (an index into
    :attr:`FingerData.loads`), at arc length ``s`` (m) of the finger,
    ``quantity`` (one of :data:`QUANTITIES`) measured as ``value`` (m or rad)
    with standard deviation ``sigma`` (same unit), from line ``line`` of the
    data file."""

    case: int
    s: float
    quantity: str
    value: float
    sigma: float
    line: int


@dataclass(frozen=True)
class FingerData:
    """Load cases (each a :class:`~design.physics.beam.PointLoad`) and what
    was measured under them, and the warning reading them raised (None: none)."""

    loads: tuple[PointLoad, ...]
    observations: tuple[Observation, ...]
    note: str | None = None

    def subset(self, keep) -> "FingerData":
        """The observations for which ``keep(observation)`` is true (the load
        cases stay, so case indices keep their meaning)."""
        return FingerData(self.loads, tuple(o for o in self.observations if keep(o)), self.note)

    @property
    def values(self) -> np.ndarray:
        return np.array([o.value for o in self.observations])

    @property
    def sigmas(self) -> np.ndarray:
        return np.array([o.sigma for o in self.observations])

    @property
    def reach(self) -> float:
        """The arc length (m) beyond which no measurement depends on EI(s): the
        largest min(measured point, load point). Past it the finger is
        unloaded or unobserved."""
        return max(min(o.s, self.loads[o.case].at) for o in self.observations)

    @property
    def max_slope(self) -> float | None:
        """The largest measured |slope| (rad), None when no slope was measured."""
        slopes = [abs(o.value) for o in self.observations if o.quantity == "psi"]
        return max(slopes) if slopes else None
