"""The bird on the belt: modes, events and impacts against closed forms."""

import math

import numpy as np
import pytest

from design.physics.bird import G, Bird, BirdDynamics, Conveyor, Legs, Loads
from design.physics.grasper import Grasper
from design.solvers.grasp.fingers import FingerForces
from design.solvers.grasp.integrate import (GAP_TOL, Grasp, IntegratorSettings, _after_event,
                                           _commit, _local_error, decide_mode, integrate)

MEAN = Bird(0.097, 0.066, 0.057, 1.8, 0.00417, "mean")
FOOTBALL = Bird(0.122, 0.066, 0.066, 0.425, 0.0016, "football")


def bare(bird=MEAN, conveyor=Conveyor(0.457), legs=Legs(0.0, 0.0), mu=0.4):
    """The bird and the belt, no fingers."""
    fingers = FingerForces(Grasper((), 0.368), bird, 2.0944, mu)
    return Grasp(BirdDynamics(bird, legs, mu), conveyor, fingers)


def energy(bird, y, v):
    """Kinetic energy in the belt's frame plus gravity's potential, J."""
    return (0.5 * bird.mass * ((y[3] - v) ** 2 + y[4] ** 2) + 0.5 * bird.inertia * y[5] ** 2
            + bird.mass * G * y[1])


def test_sitting_bird_rides_the_belt():
    grasp = bare()
    traj = integrate(grasp, np.array([-0.4, MEAN.gamma, 0.0, 0.457, 0.0, 0.0]), 0.5,
                     IntegratorSettings())
    assert traj.ok and not traj.events
    for r in traj.records:
        assert r.mode == "stick"
        assert r.y[0] == pytest.approx(-0.4 + 0.457 * r.t, abs=1e-10)
        assert r.normal == pytest.approx(MEAN.mass * G, rel=1e-12)


@pytest.mark.parametrize("belt", [0.0, 0.3])
def test_rocking_conserves_energy(belt):
    """A pitched football released on the belt rocks; rolling without slip and
    no legs: energy in the belt frame constant to the integrator's tolerance."""
    grasp = bare(FOOTBALL, Conveyor(belt), mu=1.16)
    _, D, _, _ = grasp.dyn.support(0.5)
    traj = integrate(grasp, np.array([0.0, D, 0.5, belt, 0.0, 0.0]), 2.0,
                     IntegratorSettings(rtol=1e-9, atol=1e-12))
    e = np.array([energy(FOOTBALL, r.y, belt) for r in traj.records])
    assert {r.mode for r in traj.records} == {"stick"}
    assert np.ptp(e) < 1e-6 * e[0]
    th = np.array([r.y[2] for r in traj.records])
    assert th.min() == pytest.approx(-0.5, abs=1e-4)      # rocks to the mirror pitch


def test_dropped_bird_lands_at_the_free_fall_time():
    """Released 5 cm above the belt: touch-down at sqrt(2h/g), then it rides."""
    grasp = bare()
    h = 0.05
    traj = integrate(grasp, np.array([0.0, MEAN.gamma + h, 0.0, 0.457, 0.0, 0.0]), 0.3,
                     IntegratorSettings())
    assert traj.events[0][1] == "touch-down"
    # the event fires 1 nm below the belt (GAP_TOL) at ~1 m/s: 1e-9 s late
    assert traj.events[0][0] == pytest.approx(np.sqrt(2 * h / G), abs=2e-9)
    after = [r for r in traj.records if r.t > traj.events[0][0]]
    assert all(r.mode == "stick" and r.y[4] == pytest.approx(0.0, abs=1e-12) for r in after)


def test_landing_is_a_plastic_impact():
    dyn = BirdDynamics(FOOTBALL, Legs(), 1.16)
    _, D, d1, _ = dyn.support(0.4)
    y = np.array([0.0, D, 0.4, 0.2, -0.8, -3.0])
    down = dyn.land(y)
    v_n = down[4] - down[5] * d1                       # vertical velocity of the lowest point
    assert v_n == pytest.approx(0.0, abs=1e-14)
    assert energy(FOOTBALL, down, 0.0) < energy(FOOTBALL, y, 0.0)
    assert down[3] == y[3]                             # frictionless: X momentum kept


def test_belt_braking_harder_than_friction_makes_the_bird_slip():
    """Belt slowing at 10 m/s² > µ g = 3.9 m/s²: the bird slips at once with the
    friction at -µ N, tips forward (the drag acts below its centre), and sticks
    again when its lowest point matches the belt; that happens before a sliding
    block would (0.191 s) because the forward roll carries the lowest point
    back."""
    conveyor = Conveyor(0.457, final_speed=0.1, rate=10.0, start_time=0.1)
    grasp = bare(conveyor=conveyor)
    traj = integrate(grasp, np.array([0.0, MEAN.gamma, 0.0, 0.457, 0.0, 0.0]), 0.4,
                     IntegratorSettings())
    names = [e[1] for e in traj.events]
    assert names == ["slip", "belt steady", "stick"]
    assert traj.events[0][0] == pytest.approx(0.1, abs=1e-9)
    slipping = [r for r in traj.records if r.mode == "slip"]
    assert slipping and all(r.friction == pytest.approx(-0.4 * r.normal) for r in slipping)
    assert all(grasp.dyn.slip(r.y, r.belt_speed) > 0 for r in slipping[1:])
    assert all(r.y[5] > 0 for r in slipping[1:])                  # tips forward
    t_stick = traj.events[-1][0]
    belt_steady = 0.1 + (0.457 - 0.1) / 10.0      # the belt reaches its final speed
    assert traj.events[1][0] == pytest.approx(belt_steady, abs=1e-9)
    assert belt_steady < t_stick < 0.1 + (0.457 - 0.1) / (0.4 * G)
    at_stick = min(traj.records, key=lambda r: abs(r.t - t_stick))
    assert grasp.dyn.slip(at_stick.y, at_stick.belt_speed) == pytest.approx(0.0, abs=1e-9)


def test_a_bird_its_mode_holds_on_the_belt_is_not_lifted_by_the_drift_of_that_constraint():
    """A belt mode integrates Z = D(θ), which drifts: a slipping bird 2 nm
    above the belt (twice GAP_TOL) at its stick event sticks, settled onto
    the belt (a lift is the lift-off event, N crossing zero); a bird as far
    above it, not held there, is in the air."""
    grasp = bare()
    y = np.array([0.0, MEAN.gamma + 2 * GAP_TOL, 0.0, 0.457, 0.0, 0.0])
    assert grasp.dyn.gap(y) > GAP_TOL
    mode, _, settled = _after_event(grasp, "stick", 0.0, y, "slip", 1.0)
    assert mode == "stick" and grasp.dyn.gap(settled) == pytest.approx(0.0, abs=1e-15)
    assert decide_mode(grasp, 0.0, y)[0] == "air"


def test_legs_pull_a_lifted_bird_back():
    """Leg spring k and damper c (eq. 4.28): a bird held 2 cm up with no support
    accelerates down at g + k Δz / m."""
    dyn = BirdDynamics(MEAN, Legs(30.0, 1.5), 0.4)
    from design.physics.bird import Loads
    y = np.array([0.0, MEAN.gamma + 0.02, 0.0, 0.0, 0.0, 0.0])
    acc, n, f = dyn.accelerations(y, Loads(), "air", 0.0)
    assert acc[1] == pytest.approx(-G - 30.0 * 0.02 / MEAN.mass)


def test_bdf4_run_stops_when_its_newton_fails(monkeypatch):
    """The thesis's BDF-4: a step whose Newton fails ends the run, not ok,
    saying when, instead of going on from the last iterate.
    The accelerations are made non-finite past X = -0.35 m, which the bird
    riding the belt reaches during the step from t = 0.10 s."""
    grasp = bare()
    y0 = np.array([-0.4, MEAN.gamma, 0.0, 0.457, 0.0, 0.0])
    settings = IntegratorSettings(integrator="bdf4", step=0.01)
    ok = integrate(grasp, y0, 0.1, settings)
    assert ok.ok and ok.records[-1].t == pytest.approx(0.1)
    assert ok.records[-1].y[0] < -0.35
    accelerations = grasp.dyn.accelerations

    def beyond(z, *args):
        acc, normal, friction = accelerations(z, *args)
        return (acc if z[0] < -0.35 else np.full_like(acc, np.nan)), normal, friction

    monkeypatch.setattr(grasp.dyn, "accelerations", beyond)
    run = integrate(grasp, y0, 0.3, settings)
    assert not run.ok and run.message.startswith("BDF-4 step from t = 0.1000 s failed")
    assert run.records[-1].t == pytest.approx(0.1)


def test_a_belt_that_would_pull_the_bird_down_fails_the_run(monkeypatch):
    """N >= 0 at every recorded instant. A finger force
    that jumps between the event functions' evaluation and the recorded one
    (a contact changing branch) can leave the bird in a belt mode with
    N < 0: the run stops there, not ok, naming the time and the force,
    instead of reporting a belt that pulls (the planar football once
    recorded N = -38.7 N and ended 'ok'). Here the recorded evaluation sees
    a 3 m g lift once X > -0.35 m that the event functions never see."""
    from design.physics.bird import Loads
    grasp = bare()
    evaluate = grasp.fingers.evaluate

    def jumping(t, y, commit=False):
        loads, states = evaluate(t, y, commit)
        if commit and y[0] > -0.35:
            loads = Loads(loads.qx, loads.qz + 3 * MEAN.mass * G, loads.ty)
        return loads, states

    monkeypatch.setattr(grasp.fingers, "evaluate", jumping)
    run = integrate(grasp, np.array([-0.4, MEAN.gamma, 0.0, 0.457, 0.0, 0.0]), 0.3,
                    IntegratorSettings())
    assert not run.ok and run.message.startswith("the belt pulls the bird down at t = ")
    assert run.records[-1].normal == pytest.approx(-2 * MEAN.mass * G)
    assert all(r.normal >= 0 for r in run.records[:-1])
    assert run.records[-1].y[0] > -0.35 > run.records[-2].y[0]


@pytest.mark.parametrize("k", [1, 2, 3, 4])
@pytest.mark.parametrize("h", [1e-3, 1e-2])
def test_local_error_estimate_is_milne_s_on_polynomials(k, h):
    """The BDF step's error estimate |z - p| / (k + 2), p the degree-k
    extrapolation of the last k + 1 positions: zero for motions of degree up
    to k, and for X = t^(k+1) the extrapolation misses by (k+1)! h^(k+1)
    exactly (the interpolation remainder), so the estimate is that over k + 2."""
    times = h * np.arange(k + 2)

    def state(x_of_t, t):
        return np.array([x_of_t(t), 0.05 - 0.3 * t, 0.0, 0.0, 0.0, 0.0])

    for degree in range(k + 2):
        x = lambda t, d=degree: (t + 0.2) ** d     # noqa: E731
        history = [state(x, t) for t in times[:-1]]
        error = _local_error(history, k, state(x, times[-1]))
        if degree <= k:
            assert error < 1e-12
        else:
            expected = math.factorial(k + 1) * h ** (k + 1) / (k + 2)
            assert error == pytest.approx(expected, rel=1e-6)


def test_bdf4_run_fails_where_a_step_s_local_error_is_too_large(monkeypatch):
    """The thesis's BDF-4 has no error control: a step whose estimated local
    error exceeds max_local_error ends the run, not ok, saying when. A push of
    1e4 m/s² switched on past X = -0.35 m (the bird riding the belt reaches it
    in the step from t = 0.10 s) moves it 0.5 m in one 10 ms step."""
    grasp = bare()
    y0 = np.array([-0.4, MEAN.gamma, 0.0, 0.457, 0.0, 0.0])
    settings = IntegratorSettings(integrator="bdf4", step=0.01)
    calm = integrate(grasp, y0, 0.3, settings)
    assert calm.ok and calm.local_error[0] < settings.max_local_error
    accelerations = grasp.dyn.accelerations

    def pushed(z, *args):
        acc, normal, friction = accelerations(z, *args)
        return acc + np.array([1e4 if z[0] > -0.35 else 0.0, 0.0, 0.0]), normal, friction

    monkeypatch.setattr(grasp.dyn, "accelerations", pushed)
    run = integrate(grasp, y0, 0.3, settings)
    assert not run.ok and run.message.startswith("BDF-4 step from t = 0.1000 s: estimated local")
    assert run.records[-1].t == pytest.approx(0.1)
    assert run.local_error[0] > settings.max_local_error


class PressingFromNow:
    """Fingers that trial evaluations see nothing of (waiting for a first
    touch) and whose first accepted instant starts a contact pushing the
    bird up with ``lift`` (N)."""

    states = ()

    def __init__(self, lift: float):
        self.lift, self.touched, self.pressing = lift, [], False

    def evaluate(self, t, y, commit=False):
        if commit and not self.pressing:
            self.pressing, self.touched = True, [0]
        return Loads(qz=self.lift if self.pressing else 0.0), []


def test_a_contact_starting_at_an_accepted_instant_decides_the_belt_mode_again():
    """A contact that starts at an accepted instant the integrator did not
    end for it (another event's) was not in the trials that decided the
    belt mode: where it would make the belt pull the bird down (here a lift
    of twice the bird's weight), the mode is decided again under it, and
    the bird leaves the belt, instead of the run failing there."""
    grasp = Grasp(BirdDynamics(MEAN, Legs(0.0, 0.0), 0.4), Conveyor(0.457),
                  PressingFromNow(2.0 * MEAN.mass * G))
    y = np.array([0.0, MEAN.gamma, 0.0, 0.457, 0.0, 0.0])
    record, mode, _, _, _ = _commit(grasp, 0.1, y, "stick", 0.0)
    assert mode == record.mode == "air" and record.normal == 0.0
