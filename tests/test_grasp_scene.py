"""Grasp scenes and the grasper, bird and conveyor files they reference."""

import csv
import json
from pathlib import Path

import pytest
import yaml

import design
from design.cli import main

ROOT = Path(__file__).resolve().parents[1]
SCENE = {"kind": "grasp", "grasper": "models/graspers/thesis_table_5_1.yaml",
         "bird": "models/birds/mean_1_80kg.yaml", "conveyor": {"speed": "18 in/s"},
         "drum_speed": "20 rpm", "start": {"X": 1.5}, "duration": 0.2}


def test_grasp_scene_writes_summary_and_timeseries(tmp_path):
    result = design.simulate(SCENE, out=tmp_path)
    record = result.to_dict()
    assert result.hold_time_s == 0.0 and record["summary"]["hold_windows"] == []
    assert record["bird"]["mass"] == 1.8 and record["conveyor"]["speed"] == pytest.approx(0.4572)
    assert list(result.timeseries["t_s"]) == [float(row["t_s"]) for row in
                                              csv.DictReader((tmp_path / "timeseries.csv").open())]
    rows = list(csv.DictReader((tmp_path / "timeseries.csv").open()))
    assert {"t_s", "X_m", "Z_m", "theta_rad", "N_N", "belt_friction_N", "F4a_x_N", "P4a_x_m"} <= set(rows[0])
    assert float(rows[-1]["t_s"]) == pytest.approx(0.2)


def test_finger_models_override_a_group():
    scene = {**SCENE, "finger_models": {"lower": "models/fingers/thesis_nonuniform_soft.yaml"}}
    result = design.simulate(scene)
    lower = [f for f in result.to_dict()["grasper"]["fingers"] if f["group"] == "lower"]
    assert all(f["stiffness"]["E"] == 4.8e6 for f in lower)


@pytest.mark.parametrize("change, field, text", [
    ({"conveyor": {"speed": 0.457, "final_speed": 0.6, "start_time": 0.1}},
     "conveyor.final_speed", "only decelerations"),
    ({"conveyor": {"speed": 0.457, "start_time": 0.1, "start_position": -0.1, "final_speed": 0.2}},
     "conveyor.start_time", "not both"),
    ({"finger_models": {"middle": "models/fingers/thesis_uniform.yaml"}}, "finger_models.middle",
     "no finger of the grasper"),
    ({"bird": "models/birds/ostrich.yaml"}, "bird", "ostrich.yaml' not found"),
    ({"solver": {"integrator": "euler"}}, "solver.integrator", "adaptive, bdf4"),
    ({"solver": {"integrator": "bdf4", "max_local_error": "0 m"}}, "solver.max_local_error",
     "(0, 1]"),
    ({"bird": {"semi_axes": [0.1, 0.06], "mass": 1}}, "bird.semi_axes", "expected a list of 3"),
    ({"duration": 0}, "duration", "(0, 60]"),
])
def test_bad_grasp_input(tmp_path, capsys, change, field, text):
    path = tmp_path / "scene.yaml"
    scene = {**SCENE, **change}
    for key in ("grasper", "bird"):      # files are found from the repository's root
        if isinstance(scene[key], str):
            scene[key] = str(ROOT / scene[key])
    if "finger_models" in scene:
        scene["finger_models"] = {k: str(ROOT / v) for k, v in scene["finger_models"].items()}
    path.write_text(yaml.safe_dump(scene))
    assert main(["simulate", str(path), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert f"{path}: {field}: " in err and text in err, err
    assert not (tmp_path / "out").exists()


def test_mounts_change_every_set_of_a_finger():
    """`mounts: {"3": {phi_x: 60 deg}}` (the football's finger 3, Fig 5-16)
    turns 3a, 3b and 3c alike and nothing else; an angle is set a's."""
    import math

    base = design.check({**SCENE, "grasper": str(ROOT / SCENE["grasper"])}).value
    changed = design.check({**SCENE, "grasper": str(ROOT / SCENE["grasper"]),
                            "mounts": {"3": {"phi_x": "60 deg", "angle": "80 deg"}}}).value
    for a, b in zip(base.grasper.fingers, changed.grasper.fingers):
        if a.design_name == "3":
            assert b.mount.phi_x == pytest.approx(math.radians(60))
            assert b.mount.angle - b.phase == pytest.approx(math.radians(80))
        else:
            assert b.mount == a.mount
    bad = design.check({**SCENE, "grasper": str(ROOT / SCENE["grasper"]),
                        "mounts": {"9": {"phi_x": "60 deg"}}})
    assert any(p.field == "mounts.9" and "no finger '9'" in p.message for p in bad.problems)


def test_a_finished_run_closes_with_its_numbers_and_its_validity(tmp_path, capsys):
    """The closing line gives the summary's hold and peak, and says
    'outside its validity' exactly when the summary lists a problem."""
    from design.run.grasp import summary_line

    path = tmp_path / "scene.yaml"
    path.write_text(yaml.safe_dump({**SCENE, "grasper": str(ROOT / SCENE["grasper"]),
                                    "bird": str(ROOT / SCENE["bird"])}))
    assert main(["simulate", str(path), "--out", str(tmp_path / "out"), "--quiet"]) == 0
    result = json.loads((tmp_path / "out" / "result.json").read_text())
    last = capsys.readouterr().out.strip().splitlines()[-1]
    assert last == summary_line(result)
    assert last.startswith("finished: hold 0.0000 s") and "no finger touched the bird" in last
    s = result["summary"]
    held = {**s, "hold_time_s": 0.25, "max_finger_force_N": 31.5, "max_finger_force_finger": "4a",
            "max_finger_force_time_s": 0.2,
            "validity": {**s["validity"], "fingers_through_conveyor": [
                {"finger": "5b", "time_s": 0.3, "depth_m": 0.0074}]}}
    line = summary_line({**result, "summary": held})
    assert line.startswith("finished (by a model outside its validity): hold 0.2500 s")
    assert "peak finger force 31.50 N at 4a (t = 0.200 s)" in line
    assert line.endswith("finger 5b passed 7.4 mm through the belt at 0.300 s")


def test_a_run_over_its_wall_time_budget_stops_and_says_so(tmp_path, capsys):
    """`solver: {max_wall_time: ...}`: the run stops, exit 1, `ok` false, and
    the message says where it got to; the records so far are kept."""
    import json

    scene = {**SCENE, "grasper": str(ROOT / SCENE["grasper"]),
             "bird": str(ROOT / SCENE["bird"]), "start": {"X": -0.075}, "duration": 0.6,
             "solver": {"max_wall_time": "0.2 s"}}
    path = tmp_path / "scene.yaml"
    path.write_text(yaml.safe_dump(scene))
    assert main(["simulate", str(path), "--out", str(tmp_path / "out"), "--quiet"]) == 1
    summary = json.loads((tmp_path / "out" / "result.json").read_text())["summary"]
    assert not summary["ok"] and "wall-time budget of 0.2 s" in summary["message"]
    assert f"FAILED: stopped early: {summary['message']}" in capsys.readouterr().err
    t_reached = float(summary["message"].split("at t = ")[1].split(" s")[0])
    assert 0.0 <= t_reached < 0.6


def test_a_failed_contact_fails_the_run_and_names_finger_and_time(tmp_path, monkeypatch):
    """A contact solve that does not converge inside a grasp run ends it: exit
    1, summary.ok false, the message names the finger and the time, and no
    force is counted as zero after it (the series stops there)."""
    from dataclasses import replace as replaced

    from design.io.grasp_scene import GraspSettings
    from design.io.scene_writer import grasp_spec, scene_yaml
    from design.solvers.contact.robust import RobustContact
    from tests.design_cases import short_setup

    scene = tmp_path / "short.yaml"
    scene.write_text(scene_yaml(grasp_spec(short_setup(), GraspSettings(contact_nodes=6),
                                           "short", "the short grasp")))
    solve = RobustContact.solve_frame

    def failing(self, *args, **kwargs):
        sol, cont = solve(self, *args, **kwargs)
        if sol.contact:
            return replaced(sol, converged=False, message="forced failure"), cont
        return sol, cont

    monkeypatch.setattr(RobustContact, "solve_frame", failing)
    assert main(["simulate", str(scene), "--out", str(tmp_path / "out"), "--quiet"]) == 1
    result = json.loads((tmp_path / "out" / "result.json").read_text())
    s = result["summary"]
    assert not s["ok"] and "contact failed at t = " in s["message"]
    assert "forced failure" in s["message"] and "finger " in s["message"]
    rows = (tmp_path / "out" / "timeseries.csv").read_text().splitlines()
    last_t = float(rows[-1].split(",")[0])
    assert last_t < short_setup().duration
