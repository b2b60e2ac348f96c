"""Shared fingers and loads for the tests (factories, not fixtures, so that
benchmarks can use them too)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from design.io.fingers import read_finger
from design.physics.beam import Finger, PointLoad
from design.physics.stiffness import TableI, UniformEI
from design.reproduce.grasp import load_model, thesis_setup

#: the thesis finger's I(s) (eq. 2.33) in soft rubber, and the hard rubber's E (Pa)
THESIS_SOFT = load_model(read_finger, "fingers", "thesis_nonuniform_soft.yaml")
SOFT_E = THESIS_SOFT.stiffness.E
HARD_E = load_model(read_finger, "fingers", "thesis_nonuniform_hard.yaml").stiffness.E


def uniform_finger(ei: float = 0.08, length: float = 0.203) -> Finger:
    """Thesis uniform stand-in (Table 2-1: EI = 0.08 N m^2)."""
    return Finger(length, UniformEI(ei), "uniform")


def thesis_finger(E: float = SOFT_E, length: float = 0.203) -> Finger:
    """Thesis non-uniform finger, eq. (2.33) with C = 3.2102e-9 (Table 2-3), from
    models/fingers/, in rubber of Young's modulus E (Pa); out of its plane the
    round section's rigidities (the rod's default)."""
    return Finger(length, replace(THESIS_SOFT.stiffness, E=E), "thesis")


def table_finger(length: float = 0.203) -> Finger:
    """The thesis finger's I(s) sampled at 12 points, linear between them."""
    stiff = THESIS_SOFT.stiffness
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
    return thesis_setup(t_skip, duration, lower, bird_file)


def entering_poses(seed: int, count: int, length: float = 0.203, drum_radius: float = 0.0825):
    """Random finger poses and objects: semi-axes 30-100 mm
    by 30-80 mm at any orientation, the object clear of the drum (r > r_D
    everywhere on it), and the straight finger entering it between 20 % and
    30 % of its length. Returns [(FingerPose, world-frame Ellipse)]."""
    from design.physics.contact import FingerPose
    from design.physics.ellipse import Ellipse

    rng = np.random.default_rng(seed)
    out = []
    while len(out) < count:
        pose = FingerPose(drum_radius, rng.uniform(0.0, 2 * np.pi))
        a, b, theta = rng.uniform(0.03, 0.1), rng.uniform(0.03, 0.08), rng.uniform(0.0, np.pi)
        half_height = np.hypot(a * np.sin(theta), b * np.cos(theta))
        cy = rng.uniform(-0.9, 0.9) * half_height
        # y_f = 0 enters the ellipse centred at (0, cy) where B00 x² - 2 B01 cy x + B11 cy² = 1
        B = Ellipse(a, b, (0.0, cy), theta).matrix
        qb, qc = -2 * B[0, 1] * cy, B[1, 1] * cy ** 2 - 1
        x_in = (-qb - np.sqrt(qb * qb - 4 * B[0, 0] * qc)) / (2 * B[0, 0])
        cx = rng.uniform(0.2, 0.3) * length - x_in
        c = pose.to_world(cx, cy)[:, 0]
        ell = Ellipse(a, b, (float(c[0]), float(c[1])), theta + pose.angle)
        if np.min(np.hypot(*ell.point(np.linspace(0.0, 2 * np.pi, 721)))) > drum_radius:
            out.append((pose, ell))
    return out
