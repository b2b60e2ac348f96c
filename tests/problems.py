"""Shared fingers and loads for the tests (factories, not fixtures, so that
benchmarks can use them too)."""

from __future__ import annotations

import numpy as np

from design.physics.beam import Finger, PointLoad
from design.physics.stiffness import ExponentialI, TableI, UniformEI

THESIS_I = dict(A=7.3e-8, B=-3.6551e-8, C=3.2102e-9, a=-70.87, b=-141.73)
SOFT_E, HARD_E = 4.8e6, 9.07e6


def uniform_finger(ei: float = 0.08, length: float = 0.203) -> Finger:
    """Thesis uniform stand-in (Table 2-1: EI = 0.08 N m^2)."""
    return Finger(length, UniformEI(ei), "uniform")


def thesis_finger(E: float = SOFT_E, length: float = 0.203) -> Finger:
    """Thesis non-uniform finger, eq. (2.33) with C = 3.2102e-9 (Table 2-3)."""
    return Finger(length, ExponentialI(E, **THESIS_I), "thesis")


def table_finger(length: float = 0.203) -> Finger:
    """The thesis finger's I(s) sampled at 12 points, linear between them."""
    stiff = ExponentialI(SOFT_E, **THESIS_I)
    s = np.linspace(0.0, length, 12)
    return Finger(length, TableI(SOFT_E, tuple(s), tuple(stiff.ei(s) / SOFT_E)), "table")


def table_2_1() -> tuple[Finger, PointLoad]:
    """Thesis Table 2-1: EI = 0.08, F = 15 N, α = 90°, L = 101.6 mm."""
    return uniform_finger(), PointLoad(15.0, np.pi / 2, 0.1016)


def table_2_3() -> tuple[Finger, PointLoad]:
    """Thesis Table 2-3: soft non-uniform finger, F = 15 N, α = 90°, L = 76.2 mm."""
    return thesis_finger(), PointLoad(15.0, np.pi / 2, 0.0762)


def tip_distance(a, b) -> float:
    """Distance between two solutions' load points, m."""
    return float(np.hypot(a.x[-1] - b.x[-1], a.y[-1] - b.y[-1]))


def thesis_grasp_setup(t_skip: float = 0.0, duration: float = 2.0, lower: str = "hard",
                       bird_file: str = "mean_1_80kg.yaml"):
    """The mean-bird grasp of Table 5-3 started ``t_skip`` s in (see
    design.reproduce.grasp.thesis_setup)."""
    from design.reproduce.grasp import thesis_setup

    return thesis_setup(t_skip, duration, lower, bird_file)
