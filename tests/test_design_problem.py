"""Design problem files: what is accepted, and bad input rejected with one
clear message per problem, exit status 2 and nothing written."""

from dataclasses import replace
from pathlib import Path

import pytest
import yaml

import design
from design.cli import main
from design.io.design_problem import DesignProblem
from design.run.solve import design_loop
from design.solvers.optimize.pattern_search import search

ROOT = Path(__file__).resolve().parents[1]
PROBLEM = yaml.safe_load((ROOT / "problems" / "hold_time.yaml").read_text())
SCENE = str(ROOT / "problems" / "grasp_mean_bird_hard.yaml")


def problem(**change) -> dict:
    return {**PROBLEM, "scene": SCENE, **change}


def test_shipped_problems_are_valid():
    for name in ("hold_time.yaml", "hold_time_tight_cap.yaml", "hold_time_pareto.yaml"):
        result = design.check(ROOT / "problems" / name)
        assert result.success and result.kind == "design" and result.name == name[:-5]
        assert isinstance(result.value, DesignProblem) and result.value.variables


def test_the_pattern_searchs_lattice_is_the_problems_or_64():
    solver = {"method": "pattern", "time_step": 0.005}
    assert design.check(problem(solver=solver)).value.settings.lattice == 64
    assert design.check(problem(solver={**solver, "lattice": 16})).value.settings.lattice == 16


def test_the_pattern_searchs_survey_is_the_problems_or_none():
    solver = {"method": "pattern", "time_step": 0.005}
    assert design.check(problem(solver=solver)).value.settings.survey == 0
    assert design.check(problem(solver={**solver, "survey": 8})).value.settings.survey == 8


def test_units_and_caps_are_read_in_si():
    p = design.check(problem(variables={"fingers.4.angle": ["100 deg", "120 deg"],
                                        "conveyor.rate": ["50 cm/s^2", "3 m/s^2"]},
                             cap=[{"relative_to_baseline": 0.75}, "40 N", "baseline"])).value
    lo, hi = p.variables["fingers.4.angle"]
    assert lo == pytest.approx(100 * 3.141592653589793 / 180) and hi > lo
    assert p.variables["conveyor.rate"] == pytest.approx((0.5, 3.0))
    assert [c.resolve(50.0) for c in p.caps] == pytest.approx([37.5, 40.0, 50.0])
    assert p.pareto


@pytest.mark.parametrize("change, field, text", [
    ({"variables": {"fingers.4.angle": ["-140 deg", "-160 deg"]}}, "variables.fingers.4.angle",
     "is not below upper bound"),
    ({"variables": {"fingers.4.angle": ["-160 deg", "-140 deg"]}}, "variables.fingers.4.angle",
     "do not contain the baseline's value 1.9635"),
    ({"variables": {"fingers.9.angle": [0, 1]}}, "variables.fingers.9.angle",
     "no such design variable"),
    ({"variables": {"groups.lower.stifness_scale": [0.5, 2]}},
     "variables.groups.lower.stifness_scale", "did you mean"),
    ({"cap": 0}, "cap", "outside the accepted range"),
    ({"cap": -5}, "cap", "outside the accepted range"),
    ({"cap": [30, -1]}, "cap[1]", "outside the accepted range"),
    ({"cap": {"relative_to_baseline": 0}}, "cap.relative_to_baseline", "outside"),
    ({"variables": {}}, "variables", "no design variable"),
    ({"variables": {"groups.lower.stiffness_scale": [0, 2]}},
     "variables.groups.lower.stiffness_scale", "must be > 0"),
    ({"solver": {"time_step": 2}}, "solver.time_step", "outside the accepted range"),
    ({"solver": {"lattice": 48}}, "solver.lattice", "48 is not a power of two"),
    ({"solver": {"lattice": 4}}, "solver.lattice", "outside the accepted range"),
    ({"solver": {"method": "pattern", "survey": 12}}, "solver.survey",
     "12 is not a power of two"),
    ({"solver": {"survey": 8}}, "solver.survey", "a survey needs solver.method: pattern"),
    ({"solver": {"method": "pattern", "survey": 16, "max_simulations": 16}}, "solver.survey",
     "16 Sobol points leave nothing of the budget of 16"),
    ({"solver": {"method": "simplex"}}, "solver.method",
     "'simplex' is not one of: trust-region, pattern"),
    ({"scene": "no_such_scene.yaml"}, "scene", "cannot find"),
    # a spatial scene has no other model to check against
    ({"scene": str(ROOT / "problems" / "grasp_football.yaml"), "model_check": "spatial"},
     "model_check", "'spatial' is not one of: none"),
])
def test_bad_problem_is_rejected_with_file_and_field(change, field, text):
    result = design.check(problem(**change))
    assert result.status == design.Status.INVALID and result.value is None
    assert any(p.field == field and text in p.message for p in result.problems), \
        [str(p) for p in result.problems]


def test_a_simulation_only_finger_model_is_refused_by_name(tmp_path):
    """``planar-thesis`` (the thesis's friction convention) has no NLP stage:
    a design on it is refused at the scene's finger_model, not left to fail."""
    scene = yaml.safe_load(Path(SCENE).read_text())
    for key in ("grasper", "bird", "conveyor"):
        scene[key] = str(ROOT / scene[key])
    path = tmp_path / "scene.yaml"
    path.write_text(yaml.safe_dump({**scene, "finger_model": "planar-thesis"}))
    problems = design.check(problem(scene=str(path))).problems
    assert [(p.field, "for simulations only" in p.message) for p in problems] == \
        [("scene.finger_model", True)]


def test_bad_problem_file_exits_2_and_writes_nothing(tmp_path, capsys):
    path = tmp_path / "bad.yaml"
    path.write_text(yaml.safe_dump(problem(variables={"fingers.4.angle": [1, 0],
                                                      "fingers.4.colour": [0, 1]}, cap=0)))
    out = tmp_path / "out"
    assert main(["solve", str(path), "--out", str(out), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert f"{path}: variables.fingers.4.angle" in err and "fingers.4.colour" in err
    assert f"{path}: cap" in err and "3 problems found; nothing was written" in err
    assert not out.exists()


def test_solve_and_simulate_refuse_each_others_files(tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["solve", str(ROOT / "problems" / "beam_table_2_3.yaml"), "--out", str(out)]) == 2
    assert "needs a design problem" in capsys.readouterr().err
    assert main(["simulate", str(ROOT / "problems" / "hold_time.yaml"), "--out", str(out)]) == 2
    assert "use 'design solve'" in capsys.readouterr().err
    assert not out.exists()


def test_rule_5_3_counts_the_graspers_finger_sets():
    """Eq. 5.3: v/ω = n Δx / (2π). The thesis's 0.457 m/s belt at 20 rpm with
    its three finger sets spaces birds 0.457 m apart (one per 1 s cycle); the
    rule's n defaults to the grasper's sets, so that spacing holds, and the
    same spacing with n = 1 does not."""
    from design.reproduce.grasp import thesis_setup
    from design.solvers.optimize.transcription import Rules, rule_margins
    from design.solvers.optimize.variables import parameters_of, timed_conveyor

    setup = thesis_setup(0.0, 0.6)
    setup = replace(setup, conveyor=timed_conveyor(setup.conveyor, None))
    values = parameters_of(setup)

    def worst(rules):
        return min(m for m, name in rule_margins(values, setup, rules) if "5.3" in name)

    assert worst(Rules(bird_spacing=0.457)) >= 0
    assert worst(Rules(bird_spacing=0.457, finger_sets=1)) < -0.1


def test_a_problem_built_in_python_runs_with_its_files_settings():
    """The solver policy (the loop simulator no looser than the loop's
    tolerances and no longer-stepped than the NLP's grid, the finger mesh the
    scene's unless stated) is the solve layer's: a problem built in Python
    from the file's parts, or read from the file's content as a dict, runs
    with the file's settings."""
    path = ROOT / "problems" / "hold_time.yaml"
    from_file = design.check(path).value
    data = yaml.safe_load(path.read_text())
    from_dict = design.check({**data, "scene": str(ROOT / "problems" / data["scene"])}).value
    built = DesignProblem(from_file.name, design.check(ROOT / "problems" / data["scene"]).value,
                          from_file.variables, from_file.caps, from_file.rules,
                          dict(data["solver"]), model_check="none", robustness=True)
    assert built.settings == from_file.settings == from_dict.settings
    assert built == replace(from_file, description="")
    loop, scene = from_file.settings, from_file.scene.settings
    assert loop.nlp.beam_intervals == loop.contact_nodes == scene.contact_nodes
    assert loop.simulator.max_step == loop.nlp.time_step == data["solver"]["time_step"]
    assert loop.simulator.rtol < scene.integrator.rtol
    assert loop.method == data["solver"]["method"] == "pattern"
    assert design_loop(loop) is search
