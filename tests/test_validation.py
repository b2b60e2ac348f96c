"""The grasp model against what the thesis observed: the football
experiment (§5.3, Figures 5-12 to 5-14) and the mean bird's statements
(§5.2, Figures 5-7 and 5-9), each run as `design reproduce` runs it (spatial
finger, 3 rod intervals). The thesis states these as readings ("around
0.018m"), hence 30 % where a number is compared. Where the model disagrees
with the thesis (peak finger and force, Figures 5-17 and 5-18) the
reproduction report says so and why; those are not asserted here. The
thesis's own model (planar fingers with its chapter III friction
convention, ``planar-thesis``) is asserted to give its mean-bird statement."""

import numpy as np
import pytest

from design.reproduce.grasp import football_setup, mean_bird_setup
from design.reproduce.grasp_rows import net_lift, passes, peak_family, touched
from design.solve.grasp.integrate import IntegratorSettings
from design.solve.grasp.simulation import SPATIAL_NODES, simulate_grasp
from tests import prefetch

#: keys of this module's runs for the prefetch worker (tests/prefetch.py)
FOOTBALL, MEAN_SOFT, MEAN_HARD = ("test_validation: football", "test_validation: mean bird, soft",
                                  "test_validation: mean bird, hard")
#: a reading in the thesis's text or figures
READING = 0.3


def football_run():
    return simulate_grasp(football_setup(), IntegratorSettings(), SPATIAL_NODES)


def mean_bird_run(lower: str):
    return simulate_grasp(mean_bird_setup(lower), IntegratorSettings(), SPATIAL_NODES)


@pytest.fixture(scope="module")
def football():
    return prefetch.result(FOOTBALL, football_run)


@pytest.fixture(scope="module")
def mean_soft():
    return prefetch.result(MEAN_SOFT, mean_bird_run, "soft")


@pytest.fixture(scope="module")
def mean_hard():
    return prefetch.result(MEAN_HARD, mean_bird_run, "hard")


def test_the_football_rises_about_18_mm_and_passes_without_turning_over(football):
    """Figures 5-12 to 5-14: the centre rose about 18 mm (simulated and
    measured), the ball did not turn over and passed through the grasper
    (past the drum axis at the end, never more than 10 mm back)."""
    s = football.summary
    assert football.trajectory.ok
    assert s["centre_rise_m"] == pytest.approx(0.018, rel=READING)
    assert s["max_pitch_rad"] < np.pi / 2
    assert passes(football)


def test_the_footballs_vertical_inertial_force_is_the_thesiss_estimate(football):
    """§5.3 estimates the ball's largest vertical inertial force from its Z
    trace, m A (2π/T)² = 8.52 N; ours is the largest upward force of all
    fingers less the weight."""
    assert net_lift(football) == pytest.approx(8.52, rel=READING)


def test_fingers_1_2_4_5_touch_the_arriving_mean_bird_and_3_does_not(mean_soft):
    """§5.2 on Figure 5-7 (soft lower fingers): "there is no contact between
    finger #3 and the bird"; the figure plots fingers 1, 2, 4 and 5."""
    assert touched(mean_soft) == {"1", "2", "4", "5"}


def test_hard_lower_fingers_hold_the_mean_bird_longer(mean_soft, mean_hard):
    """Figure 5-9: with hard lower fingers the belt's normal force stays at
    zero longer than with soft ones (measured: 0.323 against 0.251 s)."""
    assert mean_hard.summary["hold_time_s"] > mean_soft.summary["hold_time_s"] + 0.01


def test_the_thesiss_own_model_gives_its_mean_bird_statement():
    """Figure 5-7 (soft lower fingers) from the thesis's own model: planar
    fingers whose friction is its chapter III convention, µ on the finger
    pointing tipwards whatever the sliding (``planar-thesis``): fingers 1,
    2, 4, 5 touch, the peak is finger 4's, "in the order of 11N" (measured
    13.1 N at 4b). The same fingers with friction from the sliding
    (``planar``) peak at finger 5b, 21.4 N, as the spatial model does (21.3
    N): the friction convention separates the thesis's forces from ours."""
    run = simulate_grasp(mean_bird_setup("soft", "planar-thesis"), IntegratorSettings())
    assert run.trajectory.ok
    assert touched(run) == {"1", "2", "4", "5"}
    assert peak_family(run) == "4"
    assert run.summary["max_finger_force_N"] == pytest.approx(11.0, rel=READING)
    frictions = {f.solution.extras["friction_ratio"] for r in run.trajectory.records
                 for f in r.fingers if f.solution is not None and f.solution.contact}
    assert frictions == {run.setup.finger_friction}
    assert not any(name == "friction reverses" for _, name in run.trajectory.events)
