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
    """The mean-bird grasp of Table 5-3 (thesis grasper, hard lower fingers),
    started ``t_skip`` seconds in: the fingers advanced by ω t_skip and the bird
    by v t_skip, so that a short run covers the grasp itself."""
    from dataclasses import replace
    from pathlib import Path

    from design.io.grasp_scene import read_bird, read_conveyor, read_grasper
    from design.io.fingers import read_finger
    from design.io.reader import Reader
    from design.physics.beam import Finger
    from design.physics.bird import Legs
    from design.solve.grasp.simulation import GraspSetup

    models = Path(__file__).resolve().parents[1] / "models"
    r = Reader("tests")
    grasper = read_grasper(r, str(models / "graspers" / "thesis_table_5_1.yaml"), "g", models)
    bird = read_bird(r, str(models / "birds" / bird_file), "b", models)
    conveyor = read_conveyor(r, str(models / "conveyors" / "constant_0457.yaml"), "c", models)
    if lower == "soft":
        soft = read_finger(r, str(models / "fingers" / "thesis_nonuniform_soft.yaml"), "f", models)
        grasper = replace(grasper, fingers=tuple(
            replace(f, finger=Finger(f.finger.length, soft.stiffness)) if f.group == "lower"
            else f for f in grasper.fingers))
    r.raise_if_any()
    omega = 20 * 2 * np.pi / 60
    grasper = replace(grasper, fingers=tuple(
        replace(f, mount=replace(f.mount, angle=f.mount.angle - omega * t_skip))
        for f in grasper.fingers))
    return GraspSetup(grasper, bird, conveyor, omega, -0.457 + conveyor.speed * t_skip, 0.4, 0.4,
                      Legs(), duration)
