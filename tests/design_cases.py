"""A short grasp for the optimiser's tests: the mean bird through the thesis
grasper on a constant belt, started 0.6 s in (fingers and bird advanced so
that nothing touches before), 0.85 s long; the hold is 0.36-0.67 s."""

from __future__ import annotations

from dataclasses import replace

from design.reproduce.grasp import thesis_setup
from design.solve.optimize.variables import DesignSpace, Variable, timed_conveyor


def short_setup():
    s = thesis_setup(t_skip=0.6, duration=0.85)
    return replace(s, conveyor=timed_conveyor(s.conveyor, None))


def stiffness_space(*groups: str, lo: float = 0.5, hi: float = 1.5) -> DesignSpace:
    """Group stiffness scales as the variables (baseline 1)."""
    return DesignSpace(short_setup(), [Variable(f"groups.{g}.stiffness_scale", lo, hi, 1.0)
                                       for g in groups])
