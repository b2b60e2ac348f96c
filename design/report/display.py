"""Units as reports and printed lines show them: angles in degrees and drum
speeds in rpm, as inputs and the thesis give them; result files stay SI.

>>> shown("rad"), shown("m")
(('deg', 57.29577951308232), ('m', 1.0))
"""

from __future__ import annotations

import math

#: SI unit -> (the unit shown, the factor from SI to it)
SHOWN = {"rad": ("deg", 180.0 / math.pi), "rad/s": ("rpm", 30.0 / math.pi)}


def shown(unit: str) -> tuple[str, float]:
    """The unit a report shows a quantity of SI ``unit`` in, and the factor
    that converts it."""
    return SHOWN.get(unit, (unit, 1.0))


def degrees(value: float | None) -> float | None:
    """An angle (rad) in degrees; None stays None."""
    return None if value is None else math.degrees(value)
