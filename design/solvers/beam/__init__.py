"""Beam methods for the point-loaded elastica, chosen by name.

>>> from design.solvers.beam import METHODS
>>> sorted(METHODS)
['collocation', 'fdm', 'frisch-fay', 'shooting', 'small-deflection']
"""

from __future__ import annotations

from typing import Sequence

from design.errors import MethodUnsupportedError
from design.physics.beam import BeamSolution, Finger, PointLoad
from design.solvers.beam.base import BeamMethod
from design.solvers.beam.collocation import Collocation
from design.solvers.beam.fdm import FiniteDifference
from design.solvers.beam.frisch_fay import FrischFay
from design.solvers.beam.shooting import Shooting
from design.solvers.beam.small_deflection import SmallDeflection

METHODS: dict[str, type[BeamMethod]] = {
    "small-deflection": SmallDeflection,
    "frisch-fay": FrischFay,
    "shooting": Shooting,
    "fdm": FiniteDifference,
    "collocation": Collocation,
}

DEFAULT_METHOD = "collocation"


def make_method(name: str, finger: Finger, **options) -> BeamMethod:
    """Instantiate a method; raises MethodUnsupportedError if it cannot handle the finger."""
    method = METHODS[name](finger, **options)
    reasons = method.check()
    if reasons:
        raise MethodUnsupportedError("; ".join(reasons))
    return method


def solve_beam(finger: Finger, loads: Sequence[PointLoad], method: str = DEFAULT_METHOD,
               **options) -> list[BeamSolution]:
    """Solve the elastica of ``finger`` under each load with the named method.

    Examples
    --------
    >>> from design.physics.stiffness import UniformEI
    >>> sol = solve_beam(Finger(0.2, UniformEI(0.08)), [PointLoad(15.0, 1.5707963, 0.1016)],
    ...                  method="frisch-fay")[0]
    >>> round(sol.tip[1], 5)   # load-point deflection, m (Table 2-1)
    0.04918
    """
    return make_method(method, finger, **options).solve(loads)
