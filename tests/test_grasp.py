"""The grasp of the thesis's mean bird: accuracy against a 4x finer
run, the reach filter, the thesis's stiffness finding, the legs, the
baseline integrator. The runs start at t = 0 with the bird at Table 5-3's
X0 = -0.075 m, where finger 4a is already under it; set b arrives 1 s later,
after the bird has left, so 0.6 s covers the whole grasp."""

import math
from dataclasses import replace

import numpy as np
import pytest

from design.physics.bird import Legs
from design.solvers.grasp.integrate import IntegratorSettings
from design.solvers.grasp.simulation import simulate_grasp
from tests import prefetch
from tests.problems import thesis_grasp_setup

SKIP, DURATION = 0.0, 0.6


#: keys of this module's runs for the prefetch worker (tests/prefetch.py)
HARD, HARD_FINE = "test_grasp: hard", "test_grasp: hard, 4x finer"


def hard_run(factor: float = 1.0):
    """The hard-finger run at the default integrator's resolution times ``factor``."""
    settings = IntegratorSettings() if factor == 1.0 else IntegratorSettings().finer(factor)
    return simulate_grasp(thesis_grasp_setup(SKIP, DURATION, "hard"), settings)


@pytest.fixture(scope="module")
def hard():
    return prefetch.result(HARD, hard_run)


@pytest.fixture(scope="module")
def hard_fine():
    return prefetch.result(HARD_FINE, hard_run, 4.0)


def test_default_integrator_is_within_target_of_a_4x_finer_run(hard, hard_fine):
    """The accuracy targets: hold time within 1%, peak finger force within 2%.
    With the fingers' friction reversals located as events and each finger's
    maxima between the steps, the default run is an order of magnitude
    closer than that (``python -m benchmarks.grasp``), hence the 0.2 %
    bounds: reversals decided at the accepted steps would break them."""
    a, b = hard.summary, hard_fine.summary
    assert a["hold_time_s"] > 0.15
    assert a["hold_time_s"] == pytest.approx(b["hold_time_s"], rel=0.01)
    assert a["max_finger_force_N"] == pytest.approx(b["max_finger_force_N"], rel=0.02)
    assert a["hold_time_s"] == pytest.approx(b["hold_time_s"], rel=0.002)
    assert a["max_finger_force_N"] == pytest.approx(b["max_finger_force_N"], rel=0.002)
    assert any(name == "friction reverses" for _, name in hard.trajectory.events)
    assert a["max_finger_force_finger"] == b["max_finger_force_finger"]
    assert hard.trajectory.steps < hard_fine.trajectory.steps


@pytest.mark.parametrize("stepper", ["radau", "bdf"])
def test_the_implicit_steppers_meet_the_accuracy_targets(hard_fine, stepper):
    """radau and bdf, the steppers of stiff scenes, with their Jacobian's
    difference quotients continued from the unvaried state (the planar
    fingers from their latest trial): within the accuracy targets of the 4x
    finer rk45 run (hold 1 %, peak 2 %)."""
    run = simulate_grasp(thesis_grasp_setup(SKIP, DURATION, "hard"),
                         IntegratorSettings(stepper=stepper))
    a, b = run.summary, hard_fine.summary
    assert run.trajectory.ok, run.trajectory.message
    assert a["hold_time_s"] == pytest.approx(b["hold_time_s"], rel=0.01)
    assert a["max_finger_force_N"] == pytest.approx(b["max_finger_force_N"], rel=0.02)


def test_thesis_bdf4_with_frozen_forces_is_far_off(hard_fine):
    """The thesis's fixed-step BDF-4 with forces frozen over the step: at its
    5.6 ms step the peak force is more than 20 % too high (26 % on this scene,
    at another finger) and, run as the thesis ran it (no bound on a step's
    local error), its largest estimated local error is over the default
    bound, so with the bound the run stops, not ok; at a quarter of the step
    (benchmarks/grasp.py's second baseline) the estimate is under a quarter
    of the bound and hold and peak come within 1.5 % and 2 % of the 4x finer
    adaptive run (1.2 % and 0.7 % on this scene, where finger 5a presses on
    the belt under the bird)."""
    s = thesis_grasp_setup(SKIP, DURATION, "hard")
    thesis = IntegratorSettings(integrator="bdf4", step=5.6e-3, max_local_error=math.inf)
    coarse = simulate_grasp(s, thesis).summary
    fine = simulate_grasp(s, IntegratorSettings(integrator="bdf4", step=1.4e-3)).summary
    ref = hard_fine.summary
    assert coarse["max_finger_force_N"] > 1.2 * ref["max_finger_force_N"]
    bound = IntegratorSettings().max_local_error
    assert coarse["ok"] and coarse["local_error_estimate"]["position_m"] > bound
    assert fine["ok"] and fine["local_error_estimate"]["position_m"] < bound / 4
    checked = simulate_grasp(s, IntegratorSettings(integrator="bdf4", step=5.6e-3)).summary
    assert not checked["ok"] and "over max_local_error" in checked["message"]
    assert fine["hold_time_s"] == pytest.approx(ref["hold_time_s"], rel=0.015)
    assert fine["max_finger_force_N"] == pytest.approx(ref["max_finger_force_N"], rel=0.02)


def test_reach_filter_changes_nothing_but_the_work(hard):
    """Fingers that cannot reach the bird are not solved for: same results."""
    unfiltered = simulate_grasp(thesis_grasp_setup(SKIP, DURATION, "hard"), reach_filter=False)
    assert np.ravel(unfiltered.summary["hold_windows"]) == pytest.approx(
        np.ravel(hard.summary["hold_windows"]))
    assert unfiltered.summary["max_finger_force_N"] == pytest.approx(
        hard.summary["max_finger_force_N"], rel=1e-9)
    assert hard.skipped > 0 and unfiltered.skipped == 0
    assert hard.contact_solves <= unfiltered.contact_solves


def test_unreachable_bird_feels_no_finger():
    s = replace(thesis_grasp_setup(SKIP, 0.3, "hard"), start_x=1.5)
    run = simulate_grasp(s)
    assert run.summary["max_finger_force_N"] == 0.0 and run.summary["hold_windows"] == []
    assert run.contact_solves == 0


def test_hold_time_sensitivity_to_the_legs(hard):
    """The thesis gives no leg stiffness or damping (eq. 4.28). From none to
    twice the defaults (k = 30 N/m, c = 1.5 N s/m) the hold time changes by
    under 3% (measured: 0.2083 s at the defaults, 0.2127 s without legs,
    0.2065 s at twice the defaults)."""
    base = hard.summary["hold_time_s"]
    times = []
    for k, c in [(0.0, 0.0), (60.0, 3.0)]:
        s = replace(thesis_grasp_setup(SKIP, DURATION, "hard"), legs=Legs(k, c))
        times.append(simulate_grasp(s).summary["hold_time_s"])
    assert max(abs(t / base - 1) for t in times) < 0.03


def test_summary_fields(hard):
    s = hard.summary
    for key in ["hold_windows", "hold_time_s", "max_finger_force_N", "max_finger_force_finger",
                "max_finger_force_time_s", "centre_rise_m"]:
        assert key in s
    a, b = s["hold_windows"][0]
    # N = 0 inside the window, > 0 just outside
    inside = [r for r in hard.trajectory.records if a < r.t < b]
    assert inside and all(r.normal == 0.0 and r.mode == "air" for r in inside)
    # the peak is a recorded instant's or one located between them, never below the records'
    t_peak, _, state = hard.peak()
    assert t_peak == s["max_finger_force_time_s"] and state.magnitude == s["max_finger_force_N"]
    assert s["max_finger_force_N"] >= max(f.magnitude for r in hard.trajectory.records
                                          for f in r.fingers)
    np.testing.assert_allclose(s["centre_rise_m"],
                               max(r.y[1] for r in hard.trajectory.records) - hard.trajectory.records[0].y[1])


def test_the_belt_never_pulls_and_rise_and_clearance_are_told_apart(hard):
    """N >= 0 at every recorded instant (the belt can only push: lift-off is
    an event located where N reaches 0); the summary's centre rise is the
    centre's height gain and its belt clearance the lowest point's largest
    height above the belt, which differ when the bird pitches."""
    s = hard.summary
    normals = [r.normal for r in hard.trajectory.records]
    assert min(normals) >= 0.0 and s["min_normal_force_N"] == min(normals)
    b = hard.setup.bird
    # the lowest point of the pitched ellipse (legs free) lies sqrt(η² sin²θ + γ² cos²θ) below the centre
    gap = [r.y[1] - np.hypot(b.eta * np.sin(r.y[2]), b.gamma * np.cos(r.y[2]))
           for r in hard.trajectory.records]
    assert s["belt_clearance_m"] == pytest.approx(max(gap), abs=1e-12)
    assert s["max_pitch_rad"] > 0.05 and s["belt_clearance_m"] != s["centre_rise_m"]


def test_a_reversal_is_located_just_past_its_crossing_in_few_evaluations():
    """integrate._locate with a depth (friction reversals): the time returned
    has -2 depth <= g <= -depth, so it lies past the crossing by depth/|g'|
    to 2 depth/|g'|, and it comes from fewer evaluations than narrowing
    brentq's bracket to 1e-12 s (on a smooth margin, with 1e-11 noise as the
    Newton tolerance leaves on it)."""
    from design.solvers.grasp.integrate import REVERSAL_DEPTH, _locate
    rng = np.random.default_rng(3)
    calls = []

    def margin(t, y):
        calls.append(t)
        return 0.012 - 3.0 * t + 40.0 * t ** 2 + 1e-11 * rng.uniform(-1, 1)

    crossing = (3.0 - np.sqrt(9.0 - 4 * 40.0 * 0.012)) / 80.0
    t = _locate(margin, lambda tt: np.zeros(6), 0.0, 0.009, REVERSAL_DEPTH)
    slope = 3.0 - 80.0 * crossing
    assert 0.5 * REVERSAL_DEPTH / slope <= t - crossing <= 2.5 * REVERSAL_DEPTH / slope
    assert len(calls) <= 9
    calls.clear()
    exact = _locate(margin, lambda tt: np.zeros(6), 0.0, 0.009)   # an event: to 1e-12 s
    assert abs(exact - crossing) < 1e-11 and len(calls) > 9
