"""Chapter V trends the thesis states unambiguously (full numbers and the
disagreements in reports/reproduction/grasp.md)."""

from dataclasses import replace

from design.reproduce.grasp import FOOTBALL_START, thesis_setup
from design.solve.grasp.simulation import simulate_grasp


def test_small_bird_loses_support_earlier():
    """Table 5-5 / §5.3: 'an earlier loss of support for the small bird'
    (X0 = -0.381 m, µ = 0.4): its first N = 0 window ends before the mean bird's."""
    small = simulate_grasp(thesis_setup(0.5, 1.5, "hard", "small_1_20kg.yaml", -0.381)).summary
    mean = simulate_grasp(thesis_setup(0.5, 1.5, "hard", "mean_1_80kg.yaml", -0.381)).summary
    assert small["hold_windows"] and mean["hold_windows"]
    assert small["hold_windows"][0][1] < mean["hold_windows"][0][1] - 0.1


def test_frictionless_fingers_push_the_football_back():
    """Figure 5-16: with µ = 0 the football is pushed back (ours: X at 2 s is
    -1.53 m against -0.99 m with µ = 1.16)."""
    fb = thesis_setup(0.0, 2.0, "hard", "football.yaml", FOOTBALL_START,
                      "decelerate_figure_5_10.yaml", 1.16)
    with_friction = simulate_grasp(fb).trajectory.records[-1].y[0]
    without = simulate_grasp(replace(fb, finger_friction=0.0)).trajectory.records[-1].y[0]
    assert without < with_friction - 0.2
