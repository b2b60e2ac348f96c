"""Bad input: one clear message per problem, naming the file, the field and the
accepted range; exit status 2; nothing written."""

import json
import warnings
from pathlib import Path

import pytest
import yaml

import design
from design.cli import main
from design.errors import ProblemFileError

ROOT = Path(__file__).resolve().parents[1]
GOOD = {"kind": "beam", "finger": {"length": 0.2, "EI": 0.08},
        "load": {"F": 15, "alpha": 1.5707963, "at": 0.1}, "solver": {"method": "collocation"}}


def write(tmp_path: Path, content: dict, name: str = "scene.yaml") -> Path:
    path = tmp_path / name
    path.write_text(yaml.safe_dump(content))
    return path


def with_changes(**sections) -> dict:
    """GOOD with sections merged (load, solver) or replaced (finger, other keys)."""
    scene = json.loads(json.dumps(GOOD))
    for section, change in sections.items():
        if section in ("load", "solver"):
            scene[section].update(change)
        else:
            scene[section] = change
    return scene


#: the thesis finger's I(s) as a scene gives it inline, from the shipped model
EXPONENTIAL = yaml.safe_load((ROOT / "models/fingers/thesis_nonuniform_soft.yaml").read_text())["I"]

BAD = {
    "negative EI": (with_changes(finger={"length": 0.2, "EI": -0.08}), "finger.EI",
                    "(0, inf) N m^2"),
    "zero EI": (with_changes(finger={"length": 0.2, "EI": 0}), "finger.EI", "(0, inf)"),
    "negative E": (with_changes(finger={"length": 0.2, "E": -4.8e6,
                                        "I": {"type": "uniform", "value": 1e-8}}),
                   "finger.E", "(0, inf) Pa"),
    "zero length": (with_changes(finger={"length": 0, "EI": 0.08}), "finger.length", "(0, inf) m"),
    "negative length": (with_changes(finger={"length": "-3 in", "EI": 0.08}), "finger.length",
                        "(0, inf) m"),
    "load beyond finger": (with_changes(load={"at": 0.25}), "load.at", "(0, 0.2] m"),
    "negative force": (with_changes(load={"F": [1, -2]}), "load.F[1]", "[0, inf) N"),
    "unknown method": (with_changes(solver={"method": "newton"}), "solver.method",
                       "small-deflection, frisch-fay, shooting, fdm, collocation"),
    "unknown stiffness type": (with_changes(finger={"length": 0.2, "E": 4.8e6,
                                                    "I": {"type": "conical", "value": 1e-8}}),
                               "finger.I.type", "uniform, exponential, table"),
    "malformed unit": (with_changes(load={"alpha": "90 degs"}), "load.alpha", "did you mean 'deg'"),
    "wrong dimension": (with_changes(finger={"length": "0.2 N", "EI": 0.08}), "finger.length",
                        "not a length"),
    "unknown top-level key": (with_changes(colour="red"), "colour", "unknown key"),
    "unknown load key": (with_changes(load={"angle": 1.0}), "load.angle", "unknown key"),
    "misspelt solver key": (with_changes(solver={"node": 8}), "solver.node", "did you mean 'nodes'"),
    "closed form on non-uniform finger": (
        with_changes(finger={"length": 0.2, "E": 4.8e6, "I": EXPONENTIAL},
                     solver={"method": "frisch-fay"}), "solver.method", "uniform EI"),
    "both EI and E": (with_changes(finger={"length": 0.2, "EI": 0.08, "E": 4.8e6}), "finger.EI",
                      "not both"),
    "too few nodes": (with_changes(solver={"nodes": 1}), "solver.nodes", "[4, 200000]"),
    "table not covering finger": (
        with_changes(finger={"length": 0.2, "E": 4.8e6,
                             "I": {"type": "table", "s": [0, 0.1], "I": [2e-8, 1e-8]}}),
        "finger.I.s", "cover"),
    "negative I in exponential fit": (
        with_changes(finger={"length": 0.2, "E": 4.8e6, "I": {**EXPONENTIAL, "C": -3.2102e-8}}),
        "finger.I", "not positive"),
}


@pytest.mark.parametrize("case", list(BAD))
def test_each_bad_input_is_one_clear_problem(tmp_path, capsys, case):
    scene, field, accepted = BAD[case]
    path = write(tmp_path, scene)
    out = tmp_path / "out"
    status = main(["simulate", str(path), "--out", str(out)])
    err = capsys.readouterr().err
    assert status == 2
    assert not out.exists()
    problems = [line for line in err.splitlines() if line.startswith("error:")]
    assert len(problems) == 1, err
    assert f"{path}: {field}: " in problems[0] and accepted in problems[0], problems[0]


def test_every_problem_reported_in_one_pass(tmp_path):
    scene = with_changes(finger={"length": -1, "EI": 0.08}, load={"F": "3 furlongs", "colour": 1},
                         solver={"method": "magic"})
    with pytest.raises(ProblemFileError) as exc:
        design.simulate(write(tmp_path, scene))
    fields = sorted(p.field for p in exc.value.problems)
    assert fields == ["finger.length", "load.F", "load.colour", "solver.method"]


def test_problem_in_a_referenced_finger_file_names_that_file(tmp_path, capsys):
    finger = tmp_path / "models" / "fingers" / "bad.yaml"
    finger.parent.mkdir(parents=True)
    finger.write_text("kind: finger\nlength: 0.2\nEI: -1\n")
    scene = with_changes(finger="models/fingers/bad.yaml")
    problems_dir = tmp_path / "problems"
    problems_dir.mkdir()
    path = write(problems_dir, scene)
    assert main(["check", str(path)]) == 2
    err = capsys.readouterr().err
    assert f"{finger}: EI: -1 N m^2 is outside the accepted range (0, inf) N m^2" in err


def test_missing_finger_file_and_bad_yaml(tmp_path, capsys):
    path = write(tmp_path, with_changes(finger="models/fingers/none.yaml"))
    assert main(["check", str(path)]) == 2
    assert "finger file 'models/fingers/none.yaml' not found" in capsys.readouterr().err
    broken = tmp_path / "broken.yaml"
    broken.write_text("kind: beam\nfinger: [1, 2\n")
    assert main(["check", str(broken)]) == 2
    assert "not valid YAML at line" in capsys.readouterr().err
    empty = tmp_path / "empty.yaml"
    empty.write_text("")
    assert main(["check", str(empty)]) == 2
    assert "the file is empty" in capsys.readouterr().err


def test_shipped_models_and_problems_are_valid(capsys):
    files = sorted(str(p) for p in [*ROOT.glob("models/**/*.yaml"), *ROOT.glob("problems/*.yaml")])
    assert files
    assert main(["check", *files]) == 0, capsys.readouterr().err


def test_units_in_scene_files(tmp_path):
    scene = {"kind": "beam", "finger": {"length": "8 in", "E": "4.8 MPa",
                                        "I": {"type": "uniform", "value": "1.6667e-8 m^4"}},
             "load": {"F": "15 N", "alpha": "90 deg", "at": "4 in"},
             "solver": {"method": "frisch-fay"}}
    result = design.simulate(write(tmp_path, scene))
    case = result.to_dict()["cases"][0]
    assert case["at"] == pytest.approx(0.1016) and case["alpha"] == pytest.approx(1.5707963267948966)
    assert case["tip"]["y"] == pytest.approx(0.049184, abs=2e-5)   # EI = 0.0800016


@pytest.mark.parametrize("name", ["thesis_nonuniform_hard.yaml", "thesis_nonuniform_soft.yaml",
                                  "thesis_uniform.yaml"])
def test_written_finger_keeps_every_rigidity(name):
    """A finger written into a scene (optimum.yaml) reads back with the same
    in-plane, out-of-plane and torsional rigidity profiles."""
    import numpy as np

    from design.io.scene_writer import finger_spec
    finger = design.check(ROOT / "models" / "fingers" / name).value
    again = design.check({"kind": "finger", **finger_spec(finger)}).value
    s = np.linspace(0.0, finger.length, 7)
    for a, b in [(finger.stiffness, again.stiffness), (finger.stiffness_out, again.stiffness_out),
                 (finger.torsion_rigidity, again.torsion_rigidity)]:
        np.testing.assert_allclose(b.ei(s), a.ei(s), rtol=1e-12)


PNG = b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR\x00\x00\x00\x01"


@pytest.mark.parametrize("command", ["simulate", "solve", "tradeoff"])
def test_a_binary_file_is_named_and_nothing_is_written(tmp_path, capsys, command):
    """A PNG renamed .yaml: exit 2, a message naming the file, no output
    folder, not a UnicodeDecodeError traceback."""
    image = tmp_path / "picture.yaml"
    image.write_bytes(PNG)
    out = tmp_path / "out"
    assert main([command, str(image), "--out", str(out), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert f"error: {image}: not a text file (byte 0x89 at offset 0 is not UTF-8)" in err
    assert "1 problem found; nothing was written." in err
    assert not out.exists()


def test_check_goes_on_past_a_binary_file(tmp_path, capsys):
    """`design check a.yaml x.png b.yaml` checks all three and exits 2."""
    image = tmp_path / "x.png"
    image.write_bytes(PNG)
    a, b = ROOT / "problems" / "beam_table_2_1.yaml", ROOT / "problems" / "beam_table_2_3.yaml"
    assert main(["check", str(a), str(image), str(b)]) == 2
    captured = capsys.readouterr()
    assert captured.out.splitlines() == [f"{a}: OK", f"{b}: OK"]
    assert f"error: {image}: not a text file" in captured.err


def test_a_binary_model_file_is_named(tmp_path, capsys):
    """A scene whose finger file is binary: the problem names the finger file."""
    finger = tmp_path / "finger.yaml"
    finger.write_bytes(b"kind: finger\nlength: 0.2\n\xff\xfe")
    path = write(tmp_path, with_changes(finger=str(finger)))
    assert main(["check", str(path)]) == 2
    assert (f"error: {finger}: not a text file (byte 0xff at offset 25 is not UTF-8)"
            in capsys.readouterr().err)


@pytest.mark.parametrize("problem, key, typo", [
    ("beam_table_2_3.yaml", "load.alpha", ("alpha:", "alph:")),
    ("grasp_mean_bird_hard.yaml", "drum_speed", ("drum_speed:", "drum_sped:")),
    ("hold_time.yaml", "scene", ("scene:", "scen:")),
])
def test_a_misspelt_key_is_two_problems_each_said_once(tmp_path, capsys, problem, key, typo):
    """The unknown key and the missing one, each once, counted as 2 (a design
    problem without `scene` too, not a KeyError)."""
    path = tmp_path / problem
    path.write_text((ROOT / "problems" / problem).read_text().replace(*typo, 1))
    out = tmp_path / "out"
    command = "solve" if problem.startswith("hold_time") else "simulate"
    assert main([command, str(path), "--out", str(out)]) == 2
    err = capsys.readouterr().err.splitlines()
    assert err.count(f"error: {path}: {key}: required but missing") == 1, err
    assert [line for line in err if line.startswith("error:")][0].startswith(
        f"error: {path}: {key.replace(typo[0][:-1], typo[1][:-1])}: unknown key")
    assert err[-1] == "2 problems found; nothing was written."
    assert not out.exists()


@pytest.mark.parametrize("cwd", ["scene folder's parent", "toolkit root"])
def test_missing_model_file_names_each_folder_once(tmp_path, capsys, monkeypatch, cwd):
    from design.io.files import TOOLKIT_ROOT
    folder = tmp_path / "problems"
    folder.mkdir()
    path = write(folder, with_changes(finger="models/fingers/none.yaml"))
    monkeypatch.chdir(tmp_path if cwd == "scene folder's parent" else TOOLKIT_ROOT)
    assert main(["check", str(path)]) == 2
    err = capsys.readouterr().err
    assert (f"finger file 'models/fingers/none.yaml' not found (looked in {folder} and the "
            f"folders above it, {TOOLKIT_ROOT})\n") in err


def test_every_problem_prints_as_one_line(tmp_path, capsys):
    """Found by tests/test_scene_properties.py: a key with a carriage return,
    an empty key and a NUL character each used to break a problem over lines."""
    odd = tmp_path / "odd.yaml"
    odd.write_text('kind: beam\n"": 1\n"\\r": 2\nfinger: {length: 0.2, EI: 0.08}\n'
                   'load: {F: 1, at: 0.1, alpha: 1}\nsolver: {method: "fdm\\nx"}\n')
    nul = tmp_path / "nul.yaml"
    nul.write_text("kind: beam\x00\n")
    assert main(["check", str(odd), str(nul)]) == 2
    assert capsys.readouterr().err.splitlines() == [
        f"error: {odd}: '': unknown key (allowed: finger, load, solver, kind, name, description)",
        f"error: {odd}: '\\r': unknown key (allowed: finger, load, solver, kind, name, "
        f"description)",
        f"error: {odd}: solver.method: 'fdm\\nx' is not one of: small-deflection, frisch-fay, "
        f"shooting, fdm, collocation; did you mean 'fdm'?",
        f"error: {nul}: not valid YAML at character 11: special characters are not allowed "
        f"(code point 0x0)"]


def test_design_variables_without_a_scene_are_checked_by_name(tmp_path, capsys):
    """Found by tests/test_scene_properties.py: without `scene`, an unknown
    variable name raised KeyError."""
    path = tmp_path / "problem.yaml"
    path.write_text('kind: design\nvariables: {"3": null, conveyor.rate: [1 m/s^2, 2 m/s^2]}\n')
    assert main(["check", str(path)]) == 2
    assert capsys.readouterr().err.splitlines() == [
        f"error: {path}: scene: required but missing",
        f"error: {path}: variables.3: no such design variable (allowed: fingers.<name>.<angle|"
        f"phi_x|phi_y|length|height>, groups.<group>.stiffness_scale, conveyor.<speed|start_time|"
        f"rate|final_speed>, drum_speed, spacing, bird_spacing)"]


def test_an_overflowing_stiffness_profile_is_one_problem(tmp_path, capsys):
    """Found by tests/test_scene_properties.py: exp(a s) overflowing to inf
    passed as a warning; it is a problem, said plainly."""
    finger = {"length": 0.2, "E": 4.8e6, "I": {**EXPONENTIAL, "a": 1e4}}
    path = write(tmp_path, with_changes(finger=finger))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert main(["check", str(path)]) == 2
    # exp(1e4 s) passes the largest double (e^709.78) at s = 0.070978 m: the first
    # point of the check's 0.2 mm grid beyond it is 0.071 m
    assert capsys.readouterr().err == (
        f"error: {path}: finger.I: the rigidity from I is not positive and finite at s = "
        f"0.071 m, inside the finger (length 0.2 m); accepted: > 0 N m^2 on [0, length]\n")


def test_a_written_grasper_reads_back_with_its_finger_sets():
    """A grasp written into a scene (optimum.yaml) reads back as the same
    grasper: every finger at the same mount, each copy still a copy of its
    designed finger (what belt slots and design variables name) and the
    drums' number of sets (what the line-speed rules use); a grasper whose
    sets are not copies (one changed alone) is written finger by finger."""
    from dataclasses import replace

    from design.io.grasp_scene import GraspSettings
    from design.io.scene_writer import grasp_spec
    from design.run.grasp import setup_of

    setup = setup_of(design.check(ROOT / "problems" / "grasp_mean_bird_hard_spatial.yaml").value)
    assert setup.grasper.sets == 3
    spec = grasp_spec(setup, GraspSettings(), "again", "")
    assert spec["grasper"]["sets"] == 3 and len(spec["grasper"]["fingers"]) == 5
    again = setup_of(design.check(spec).value).grasper
    assert again.sets == 3
    assert [(f.name, f.design_name, f.mount) for f in again.fingers] == \
        [(f.name, f.design_name, f.mount) for f in setup.grasper.fingers]
    moved = setup.grasper.with_finger(7, replace(setup.grasper.fingers[7], mount=replace(
        setup.grasper.fingers[7].mount, angle=setup.grasper.fingers[7].mount.angle + 0.1)))
    spec = grasp_spec(replace(setup, grasper=moved), GraspSettings(), "moved", "")
    assert "sets" not in spec["grasper"] and len(spec["grasper"]["fingers"]) == 15
