"""Contact scenes through the file format, the API and the command."""

import json
from pathlib import Path

import pytest
import yaml

import design
from design.cli import main

ROOT = Path(__file__).resolve().parents[1]
SCENE = {"kind": "contact", "finger": {"length": 0.203, "EI": 0.08}, "drum": {"radius": 0.0825},
         "finger_angle": "126 deg",
         "object": {"semi_axes": [0.0991, 0.0673], "center": [-0.1016, 0.184]},
         "friction": 0.6, "sliding": "push"}


def test_contact_scene_result_fields(tmp_path):
    result = design.simulate(SCENE, out=tmp_path)
    case = result.to_dict()["cases"][0]
    for key in ["contact", "force", "force_vector", "point", "point_world", "psi", "alpha",
                "arc_length", "tip_contact", "sliding", "shape", "converged", "iterations"]:
        assert key in case
    assert case["contact"] and case["sliding"] == "push" and case["converged"]
    # force on the object, world frame: magnitude equals the force
    assert sum(v * v for v in case["force_vector"]) ** 0.5 == pytest.approx(case["force"])
    assert (tmp_path / "cases.csv").read_text().count("\n") == 2


def test_pass_with_lists_and_units(tmp_path):
    scene = {**SCENE, "finger_angle": ["144 deg", "126 deg", "108 deg"],
             "object": {"semi_axes": ["99 mm", "67 mm"],
                        "center": [[-0.1778, 0.184], [-0.1016, 0.184], [-0.0254, 0.184]]},
             "sliding": "auto", "motion": {"drum_speed": "20 rpm", "object_velocity": [0.508, 0]}}
    result = design.simulate(scene)
    forces = result.forces_N
    assert len(forces) == 3 and forces[0] < forces[1] < forces[2]
    assert {c["friction"] for c in result.to_dict()["cases"]} == {"baseward"}


def test_thesis_methods_run_from_files(tmp_path):
    for method in ["thesis-1", "thesis-2"]:
        result = design.simulate({**SCENE, "solver": {"method": method}})
        assert result.converged == 1 and result.method == method


@pytest.mark.parametrize("change, field, text", [
    ({"finger_angle": [1.0, 2.0], "object": {"semi_axes": [0.1, 0.07],
                                             "center": [[0, 0.2], [0, 0.2], [0, 0.2]]}},
     "object.center", "3 centres for 2 finger angles"),
    ({"solver": {"method": "thesis-1"}, "sliding": "auto"}, "sliding", "push or pull"),
    ({"solver": {"method": "robust", "step": 0.3}}, "solver.step", "not an option of method"),
    ({"friction": -0.1}, "friction", "[0, 10]"),
    ({"object": {"semi_axes": [0.1, -0.07], "center": [0, 0.2]}}, "object.semi_axes", "positive"),
    ({"sliding": "drag"}, "sliding", "push, pull, auto"),
    ({"motion": {"drum_speed": "20 rpm", "object_velocity": [0.5, 0], "spin": 1}},
     "motion.spin", "did you mean 'object_spin'"),
])
def test_bad_contact_input(tmp_path, capsys, change, field, text):
    path = tmp_path / "scene.yaml"
    path.write_text(yaml.safe_dump({**SCENE, **change}))
    assert main(["simulate", str(path), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert f"{path}: {field}: " in err and text in err
    assert not (tmp_path / "out").exists()


def test_shipped_contact_problems_run(tmp_path):
    result = design.simulate(ROOT / "problems" / "contact_pass.yaml", out=tmp_path)
    peak = max(result.forces_N)
    assert 29 < peak < 33
    written = json.loads((tmp_path / "result.json").read_text())
    assert written["kind"] == "contact" and len(written["cases"]) == 28
