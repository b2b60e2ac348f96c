"""What a grasp run counts and sums: gravity, the hold, a jam, and the fingers'
loads on the bird, each against numbers the code does not supply itself."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from design.io.scene import load_scene
from design.physics.bird import Bird, BirdDynamics, Legs, Loads
from design.run.grasp import setup_of
from design.solvers.grasp.fingers import FingerForces, FingerState
from design.solvers.grasp.integrate import Record, Trajectory
from design.solvers.grasp.simulation import GraspRun, summarise

ROOT = Path(__file__).resolve().parents[1]

#: the thesis's g (§4.4), m/s²: standard gravity 9.80665 rounded as the thesis does
THESIS_G = 9.81
MEAN = Bird(0.097, 0.066, 0.057, 1.8, 0.00417, "mean")


def test_a_free_bird_falls_at_g():
    """Off the belt with no finger and no legs: Ẍ = 0, Z̈ = -9.81 m/s², θ̈ = 0."""
    acc, normal, friction = BirdDynamics(MEAN, Legs(0.0, 0.0), 0.4).accelerations(
        np.array([0.0, 0.2, 0.3, 0.457, -1.0, 0.5]), Loads(), "air", 0.0)
    assert acc == pytest.approx([0.0, -THESIS_G, 0.0], abs=1e-12)
    assert normal == friction == 0.0


@pytest.mark.parametrize("legs", [Legs(0.0, 0.0), Legs()])
def test_a_sitting_bird_weighs_mg_on_the_belt(legs):
    """Level, at rest on a steady belt (the legs at their rest length): N = m g
    = 17.658 N, no friction, no acceleration."""
    acc, normal, friction = BirdDynamics(MEAN, legs, 0.4).accelerations(
        np.array([0.0, MEAN.gamma, 0.0, 0.457, 0.0, 0.0]), Loads(), "stick", 0.0)
    assert normal == pytest.approx(1.8 * THESIS_G, rel=1e-12)
    assert friction == pytest.approx(0.0, abs=1e-12)
    assert acc == pytest.approx([0.0, 0.0, 0.0], abs=1e-12)


def mean_bird_setup(duration: float = 1.0):
    return replace(setup_of(load_scene(ROOT / "problems" / "grasp_mean_bird_soft.yaml")),
                   duration=duration)


def synthetic_run(modes: list[tuple[float, str]], end_speed: float = 0.457,
                  touch_downs: tuple = ()) -> GraspRun:
    """A run whose belt modes change at the given times (s), sampled every 10
    ms, no finger touching; the bird moves at ``end_speed`` (m/s) at the
    end. The touch-downs are where the bird comes back to the belt."""
    setup = mean_bird_setup(modes[-1][0])
    times = np.round(np.arange(0.0, modes[-1][0] + 1e-9, 0.01), 10)
    bounds = [t for t, _ in modes]
    traj = Trajectory()
    for t in times:
        k = min(int(np.searchsorted(bounds, t, side="right")), len(modes) - 1)
        mode = modes[k][1]
        y = np.array([-0.5 + 0.457 * t, MEAN.gamma, 0.0, 0.457, 0.0, 0.0])
        if t == times[-1]:
            y[3] = end_speed
        traj.records.append(Record(float(t), y, mode, 0.0 if mode == "air" else 17.7, 0.0,
                                   0.457, [FingerState() for _ in setup.grasper.fingers]))
    traj.events = [(t, "touch-down") for t in touch_downs]
    return GraspRun(setup, traj, None, 0, 0, 0.0)


def test_the_hold_is_the_longest_window_the_bird_is_put_back_from():
    """Windows [0.10, 0.15] and [0.30, 0.50] s, both ended by the belt taking
    the bird back: the hold is the later, longer one, 0.20 s; in all 0.25 s."""
    s = summarise(synthetic_run([(0.10, "stick"), (0.15, "air"), (0.30, "stick"),
                                 (0.50, "air"), (0.80, "stick")]))
    assert np.ravel(s["hold_windows"]) == pytest.approx([0.10, 0.15, 0.30, 0.50])
    assert s["hold_time_s"] == pytest.approx(0.20)
    assert s["total_hold_s"] == pytest.approx(0.25)
    assert not s["jammed"] and s["jam"] == []


def test_a_bird_held_to_the_end_is_jammed_and_holds_nothing():
    """The bird still off the belt when the run ends: its windows, the short
    one it came back from included, do not count; a jam that says so."""
    s = summarise(synthetic_run([(0.10, "stick"), (0.15, "air"), (0.30, "stick"),
                                 (0.80, "air")]))
    assert s["hold_time_s"] == 0.0 and s["jammed"]
    assert s["jam"][0].startswith("the bird is still held off the belt when the run ends")


def test_a_bird_pushed_back_is_jammed_and_holds_nothing():
    """Put back on the belt but moving upstream at the end: not carried on."""
    s = summarise(synthetic_run([(0.10, "stick"), (0.30, "air"), (0.80, "stick")],
                                end_speed=-0.1))
    assert s["hold_time_s"] == 0.0 and s["jammed"]
    assert s["jam"] == ["the bird is not carried on: it moves at -0.100 m/s along the belt "
                        "when the run ends"]


@pytest.mark.parametrize("model", ["spatial", "planar"])
def test_the_loads_on_the_bird_are_every_touching_finger_and_its_mirror(model):
    """At a state where fingers 1b, 2b and 4b touch the mean bird (and the
    fives rest on the belt): Q_X, Q_Z and T_Y are the sum over every
    touching finger and its mirror on the left drum (Y of force and point
    negated) of the forces and of (r × f)_Y, r from the bird's centre
    (to 1e-12 relative)."""
    s = mean_bird_setup()
    fingers = FingerForces(s.grasper, s.bird, s.drum_speed, s.finger_friction, None,
                           intervals=3, model=model, belt=s.belt,
                           belt_friction=s.finger_belt_friction)
    y = np.array([s.start_x + 0.457 * 1.15, s.bird.gamma + 0.012, 0.1, 0.457, 0.0, 0.0])
    loads, states = fingers.evaluate(1.15, y, commit=True)
    touching = [st for st in states if st.magnitude > 0]
    assert {gf.name for gf, st in zip(s.grasper.fingers, states) if st.magnitude > 0} == \
        {"1b", "2b", "4b"}
    centre = np.array([y[0], 0.0, y[1]])
    mirror = np.array([1.0, -1.0, 1.0])
    total = np.zeros(3)
    for st in touching:
        for f, p in ((st.force, st.point), (st.force * mirror, st.point * mirror)):
            total += [f[0], f[2], np.cross(p - centre, f)[1]]
    assert [loads.qx, loads.qz, loads.ty] == pytest.approx(total, rel=1e-12, abs=1e-12)
    assert loads.qz > 0
