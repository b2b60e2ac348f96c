"""The line's speed as a design variable: drum speed, belt speed and bird
spacing tied by eq. 5.3 (design/solvers/optimize/variables.py), the bird
meeting its finger set as in the baseline scene."""

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
import yaml

import design

from design.errors import ProblemFileError
from design.io.scene import load_scene
from design.run.grasp import setup_of
from design.run.line import pareto
from design.solvers.optimize.line import broken, faster, included_angle, max_sets, rate
from design.solvers.optimize.trust_region import verify
from design.solvers.optimize.variables import (DesignSpace, Variable, parameters_of,
                                              synchronised, timed_conveyor)
from tests.design_cases import LOOP, editable, sharing_simulations, stiffness_space

SCENE = Path(__file__).resolve().parents[1] / "problems" / "grasp_mean_bird_hard_spatial.yaml"
MODELS = SCENE.parents[1] / "models"
RPM = 2 * np.pi / 60


@pytest.fixture
def shared_simulations():
    with sharing_simulations():
        yield


@pytest.fixture(scope="module")
def baseline():
    """The main job's scene, its constant belt timed as a design space's is."""
    setup = setup_of(load_scene(SCENE))
    return replace(setup, conveyor=timed_conveyor(setup.conveyor, None))


def line_space(setup, *names):
    base = parameters_of(setup)
    bounds = {"drum_speed": (10 * RPM, 90 * RPM), "bird_spacing": (0.2, 0.8),
              "conveyor.speed": (0.2, 1.5)}
    return DesignSpace(setup, [Variable(n, *bounds[n], base[n]) for n in names])


def at(space, **values):
    """The scaled design with these SI values (the rest at the baseline)."""
    return space.scale({**space.base_values, **values})


def test_the_thesis_line_is_one_bird_a_second_at_three_sets(baseline):
    """Table 5-1's grasper (three sets) at 20 rpm on the 0.457 m/s belt: eq.
    5.3 gives the 0.457 m spacing of a 1 s cycle (§5.3), and the arrival scene
    starts the bird that spacing upstream of Table 5-3's X0 = -0.075 m."""
    values = parameters_of(baseline)
    assert baseline.grasper.sets == 3
    assert values["bird_spacing"] == pytest.approx(0.457, rel=1e-3)
    assert baseline.start_x == pytest.approx(-0.075 - values["bird_spacing"], abs=1e-3)


def test_the_baseline_line_leaves_the_scene_as_it_is(baseline):
    """At the baseline's line the scene is the one a design space without
    the line's variables builds, bit for bit, whichever parameter follows."""
    fixed = DesignSpace(baseline, [Variable("groups.upper.stiffness_scale", 0.5, 2.0, 1.0)])
    assert fixed.follows is None
    reference = fixed.setup(fixed.scale(fixed.base_values))
    for names, follows in ((("drum_speed", "bird_spacing"), "conveyor.speed"),
                           (("drum_speed",), "bird_spacing")):
        space = line_space(baseline, *names)
        assert space.follows == follows
        assert space.setup(space.scale(space.base_values)) == reference


@pytest.mark.parametrize("names, change", [
    (("drum_speed", "bird_spacing"), {"drum_speed": 60 * RPM}),
    (("drum_speed", "bird_spacing"), {"drum_speed": 40 * RPM, "bird_spacing": 0.35}),
    (("drum_speed",), {"drum_speed": 30 * RPM}),
    (("conveyor.speed", "drum_speed"), {"conveyor.speed": 0.9, "drum_speed": 30 * RPM})])
def test_a_moved_line_keeps_eq_5_3_and_the_bird_meeting_its_finger_set(baseline, names,
                                                                     change):
    """Whatever two of the line's parameters move, the third follows by eq.
    5.3 (2 pi v = n dx omega), the bird is where the baseline's bird is when
    the next finger set reaches the layout's angles (one period 2 pi/(n
    omega) after the start), and the run covers the baseline's time after
    it or its turn of the drum, the longer."""
    space = line_space(baseline, *names)
    d = at(space, **change)
    values = space.values(d)
    setup = space.setup(d)
    n, v, w = 3, setup.conveyor.speed, setup.drum_speed
    assert 2 * np.pi * v == pytest.approx(n * values["bird_spacing"] * w, rel=1e-12)
    for name, value in change.items():
        assert values[name] == pytest.approx(value, rel=1e-12)
    assert setup.conveyor.final_speed == v                    # the constant belt stays one
    period, base_period = 2 * np.pi / (n * w), 2 * np.pi / (n * baseline.drum_speed)
    met = baseline.start_x + baseline.conveyor.speed * base_period
    assert setup.start_x + v * period == pytest.approx(met, abs=1e-12)
    after, base_after = setup.duration - period, baseline.duration - base_period
    assert after == pytest.approx(max(base_after, base_after * baseline.drum_speed / w))


def test_three_line_variables_or_a_trust_region_loop_are_refused(tmp_path):
    base = {"kind": "design", "scene": str(SCENE),
            "solver": {"method": "pattern"}}
    three = {"drum_speed": ["10 rpm", "60 rpm"], "bird_spacing": ["0.3 m", "0.6 m"],
             "conveyor.speed": ["0.3 m/s", "1 m/s"]}
    with pytest.raises(ProblemFileError, match="at most two of them"):
        load_scene({**base, "variables": three})
    with pytest.raises(ProblemFileError, match="solver.method"):
        load_scene({**base, "solver": {}, "variables": {"drum_speed": ["10 rpm", "60 rpm"]}})
    with pytest.raises(ValueError, match="at most two"):
        line_space(setup_of(load_scene(SCENE)), "drum_speed", "bird_spacing", "conveyor.speed")


def test_the_line_rate_and_eq_5_4(baseline):
    """60 birds/min for the thesis's three sets at 20 rpm, 180 (the kill
    line) at 60 rpm; Table 5-1's set spans 45 deg (90 to 135 deg), so eq. 5.4
    allows at most 8 sets."""
    assert rate(3, 20 * RPM) == pytest.approx(60.0)
    assert rate(3, 60 * RPM) == pytest.approx(180.0)
    assert np.degrees(included_angle(baseline.grasper)) == pytest.approx(45.0)
    assert max_sets(baseline.grasper) == 8


def test_more_sets_are_the_designed_set_mounted_again(baseline):
    """n sets: every designed finger n times, 2 pi/n apart, set a as designed."""
    four = baseline.grasper.with_sets(4)
    assert four.sets == 4 and len(four.fingers) == 4 * 5
    angles = {gf.name: gf.mount.angle for gf in four.fingers}
    assert angles["3a"] == pytest.approx(baseline.grasper.fingers[2].mount.angle)
    assert angles["3b"] - angles["3a"] == pytest.approx(np.pi / 2)
    assert four.with_sets(3) == baseline.grasper


def test_more_sets_meet_the_bird_where_the_scene_does(baseline):
    """Four sets at the same drum and belt speed: the bird starts one
    (shorter) period upstream of where the three-set scene's bird meets its
    set, and the 0.457 m/s belt now carries birds 0.343 m apart."""
    four = synchronised(replace(baseline, grasper=baseline.grasper.with_sets(4)), baseline)
    period3, period4 = 2 * np.pi / (3 * baseline.drum_speed), 2 * np.pi / (4 * baseline.drum_speed)
    v = baseline.conveyor.speed
    assert four.start_x + v * period4 == pytest.approx(baseline.start_x + v * period3, abs=1e-12)
    assert parameters_of(four)["bird_spacing"] == pytest.approx(0.457 * 3 / 4, rel=1e-3)
    assert four.duration - period4 == pytest.approx(baseline.duration - period3)


def fake(base, drum_rpm: float, hold: float, extra_force: float = 0.0, jam: bool = False):
    """A copy of a simulated design with another drum speed, hold and peak."""
    out = editable(base)
    run = out.members[0].run
    run.setup = replace(run.setup, drum_speed=drum_rpm * RPM)
    s = run.summary
    s["hold_time_s"] = hold
    s["max_force_per_finger_N"] = {k: f + extra_force for k, f in
                                   s["max_force_per_finger_N"].items()}
    s["jam"] = ["the bird is still held off the belt when the run ends"] if jam else []
    return out


def test_throughput_ranks_rules_then_rate_then_hold(shared_simulations):
    """For ``objective: throughput`` a design that keeps the cap, the fold
    forces and no jam beats one that does not; among those, reaching the
    hold asked beats not (else the longer hold); among those, the faster
    line; at one rate the longer hold by more than the band."""
    space = stiffness_space("lower", hi=2.0)
    base = verify(space, space.scale(space.base_values), LOOP)
    cap, asked = [base.peak * 1.5], 0.1
    slow, fast = fake(base, 20, 0.15), fake(base, 30, 0.12)
    short_fast = fake(base, 40, 0.05)
    pressing = fake(base, 40, 0.3, extra_force=base.peak)
    jammed = fake(base, 40, 0.3, jam=True)
    assert faster(fast, slow, cap, asked, 1e-4) and not faster(slow, fast, cap, asked, 1e-4)
    assert faster(slow, short_fast, cap, asked, 1e-4)          # the hold asked first
    assert faster(short_fast, pressing, cap, asked, 1e-4)      # the cap before the hold
    assert faster(pressing, jammed, cap, asked, 1e-4)          # a jam is the furthest off
    assert faster(fake(base, 20, 0.1502), slow, cap, asked, 1e-4)
    assert not faster(fake(base, 20, 0.1500 + 5e-5), slow, cap, asked, 1e-4)
    assert faster(fake(base, 40, 0.06), short_fast, cap, asked, 1e-4)  # nearer the hold


def test_the_rules_a_design_breaks_are_named_by_bird_finger_and_rule(shared_simulations):
    space = stiffness_space("lower", hi=2.0)
    base = verify(space, space.scale(space.base_values), LOOP)
    bird = base.population.members[0].name
    assert broken(base, [base.peak * 1.5], 0.0) == []
    finger = base.run.summary["max_finger_force_finger"]
    named = broken(fake(base, 20, 0.05, extra_force=base.peak, jam=True),
                   [base.peak * 1.5], 0.1)
    assert named[0] == f"{bird}: the bird is still held off the belt when the run ends"
    assert any(n.startswith(f"{bird}: finger {finger} presses") for n in named)
    assert named[-1] == f"{bird}: held 0.0500 s, under the 0.1 s asked"


def test_the_pareto_front_keeps_only_undominated_unjammed_designs():
    rows = [{"line_rate_per_min": r, "hold_time_s": h, "max_finger_force_N": p,
             "jammed_birds": j} for r, h, p, j in
            [(60, 0.3, 20, 0), (60, 0.2, 20, 0), (90, 0.2, 25, 0), (90, 0.2, 30, 0),
             (120, 0.1, 15, 0), (180, 0.4, 10, 1)]]
    front = pareto(rows)
    assert [(r["line_rate_per_min"], r["hold_time_s"], r["max_finger_force_N"])
            for r in front] == [(60, 0.3, 20), (90, 0.2, 25), (120, 0.1, 15)]


LINE = {"objective": "throughput", "min_hold": "0.2 s"}


@pytest.mark.parametrize("change, field", [
    ({"min_hold": "0.2 s"}, "min_hold"),                      # not a throughput problem
    ({**LINE, "finger_sets": [3, 9]}, "finger_sets[1]"),      # eq. 5.4: at most 8
    ({**LINE, "finger_sets": [3, 3]}, "finger_sets"),
    ({**LINE, "solver": {}}, "solver.method"),
    ({**LINE, "solver": {"method": "pattern", "survey": 8}}, "solver.survey"),
    ({**LINE, "min_hold": "2 s"}, "min_hold"),                # longer than the run
    ({**LINE, "objective": "speed"}, "objective")])
def test_line_problems_refuse_bad_input_by_field(change, field):
    base = {"kind": "design", "scene": str(SCENE), "solver": {"method": "pattern"},
            "variables": {"drum_speed": ["20 rpm", "60 rpm"]}}
    with pytest.raises(ProblemFileError) as info:
        load_scene({**base, **change})
    assert any(p.field == field for p in info.value.problems), str(info.value)


@pytest.mark.slow
def test_a_line_study_end_to_end(tmp_path):
    """``design solve`` of a small throughput problem (the planar finger, one
    bird, two numbers of sets, eight designs each): every case's rate is 60 n
    omega / 2 pi of its design, the answer is the fastest verified case, the
    Pareto front is undominated, and the files are written."""
    problem = {"kind": "design", "name": "line_small",
               "scene": {**{k: v for k, v in yaml.safe_load(SCENE.read_text()).items()
                            if k not in ("kind", "name", "description")},
                         "finger_model": "planar", "grasper": str(MODELS / "graspers" /
                                                                 "thesis_table_5_1.yaml"),
                         "bird": str(MODELS / "birds" / "mean_1_80kg.yaml"),
                         "conveyor": str(MODELS / "conveyors" / "constant_0457.yaml")},
               "objective": "throughput", "min_hold": "0.1 s", "finger_sets": [3, 4],
               "variables": {"drum_speed": ["20 rpm", "40 rpm"],
                             "groups.lower.stiffness_scale": [0.5, 2.0]},
               "cap": {"relative_to_baseline": 1.5}, "model_check": "none",
               "solver": {"method": "pattern", "max_simulations": 8}}
    result = design.solve(problem, out=tmp_path, workers=1).to_dict()
    cases = result["line"]["cases"]
    for case in cases:
        assert case["line_rate_per_min"] == pytest.approx(
            case["finger_sets"] * case["drum_speed_rpm"], rel=1e-12)
    verified = [c for c in cases if c["status"] == "verified"]
    if verified:
        assert result["line_rate_per_min"] == max(c["line_rate_per_min"] for c in verified)
    front = result["pareto"]
    assert front and pareto(front) == front
    for name in ("result.json", "line.csv", "pareto.csv", "birds.csv", "report.html"):
        assert (tmp_path / name).exists()
