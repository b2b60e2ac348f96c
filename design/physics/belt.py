"""Where the fingers can touch the conveyor: the belt's surface as the fingers see it.

The belt's surface is the plane Z = 0 of the world frame (MODEL.md,
"Frames"), moving along X at the conveyor's speed. A finger whose tip would
pass below it presses on it instead (design/solvers/contact/spatial_belt.py).

By default the belt is solid and wider than any finger reaches. A scene can
say otherwise: ``width`` (m) makes it a strip |Y| ≤ width / 2, beside
which the fingers pass freely, and ``slots`` names designed fingers (every
set's copy) that pass through slots cut for them, as on a slotted pallet.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Belt:
    """The belt surface's extent for the fingers: ``width`` (m; inf: solid)
    and the designed fingers that pass through slots in it."""

    width: float = np.inf
    slots: frozenset[str] = frozenset()

    @property
    def solid(self) -> bool:
        return np.isinf(self.width) and not self.slots

    def touches(self, design_name: str, y: float) -> bool:
        """Whether a finger (by design name) meets the belt at world Y = ``y`` (m)."""
        return design_name not in self.slots and abs(y) <= self.width / 2

    def describe(self) -> dict:
        return {"width_m": None if np.isinf(self.width) else self.width,
                "slots": sorted(self.slots)}
