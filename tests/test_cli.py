"""design simulate / design check and the Python API, as a user runs them."""

import csv
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

import design
from design.cli import main
from design.io.results import jsonable

ROOT = Path(__file__).resolve().parents[1]


def test_simulate_writes_result_json_that_equals_the_api(tmp_path):
    scene = ROOT / "problems" / "beam_table_2_3.yaml"
    out = tmp_path / "out"
    assert main(["simulate", str(scene), "--out", str(out), "--quiet"]) == 0
    written = json.loads((out / "result.json").read_text())
    api = jsonable(design.simulate(scene).to_dict())
    assert written.pop("solve_time_s") > 0 and api.pop("solve_time_s") > 0
    assert written == api
    case = written["cases"][0]
    for key in ["F", "alpha", "at", "tip", "shape", "error_estimate", "converged", "branch"]:
        assert key in case
    assert set(case["shape"]) >= {"s", "x", "y", "psi"}
    assert written["kind"] == "beam" and written["status"] == "finished"
    assert case["converged"] and case["error_estimate"] < 1e-8
    rows = list(csv.DictReader((out / "cases.csv").open()))
    assert float(rows[0]["tip_y_m"]) == pytest.approx(case["tip"]["y"])


def test_sweep_result_has_one_case_per_load(tmp_path):
    result = design.simulate(ROOT / "problems" / "beam_sweep.yaml", out=tmp_path)
    cases = result.to_dict()["cases"]
    forces = [c["F"] for c in cases]
    assert forces == [0, 2.5, 5, 7.5, 10, 12.5, 15, 17.5, 20, 22.5, 25, 27.5, 30]
    assert result.cases == result.converged == 13
    assert cases[0]["branch"] == "straight"
    assert all(c["branch"] == "primary" for c in cases[1:])
    assert result.files[0] == tmp_path / "result.json" and all(p.is_file() for p in result.files)
    assert json.loads(result.files[0].read_text()) == json.loads(result.to_json())


def test_default_output_folder_is_reports_scene_name(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(["simulate", str(ROOT / "problems" / "beam_table_2_1.yaml"), "--quiet"]) == 0
    assert (tmp_path / "reports" / "beam_table_2_1" / "result.json").is_file()


def test_console_command_is_installed():
    """The `design` entry point runs as a process (exit 0, files listed)."""
    exe = Path(sys.executable).with_name("design")
    cmd = [str(exe)] if exe.exists() else [sys.executable, "-m", "design"]
    done = subprocess.run([*cmd, "check", str(ROOT / "problems" / "beam_table_2_1.yaml")],
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0 and "OK" in done.stdout


def test_the_package_is_the_api_and_the_version_is_shown(capsys):
    """`import design` offers the five functions and the result types, and
    loads no solver until one is called; `design --version` prints the
    package's version."""
    done = subprocess.run([sys.executable, "-c", "import sys, design; "
                           "print(sorted(design.__all__), dir(design) == sorted(design.__all__), "
                           "'casadi' in sys.modules)"], capture_output=True, text=True,
                          timeout=60, cwd=ROOT)
    assert done.stdout.split("] ")[1].split() == ["True", "False"]
    for name in ("simulate", "solve", "fit", "check", "animate", "Status", "DesignResult"):
        assert name in done.stdout
    import design.calibration.belt                   # the subpackages do not shadow the API
    import design.solvers.optimize.trust_region
    from design import api
    assert (design.simulate, design.solve, design.fit, design.check, design.animate) == \
        (api.simulate, api.solve, api.fit, api.check, api.animate)
    with pytest.raises(SystemExit) as exit_:
        main(["--version"])
    assert exit_.value.code == 0 and capsys.readouterr().out.strip() == f"design {design.__version__}"


def _must_not_run(*args, **kwargs):
    raise AssertionError("the run started although its output folder cannot be written")


@pytest.fixture
def nothing_runs(monkeypatch):
    """Every command's work replaced by a failure: the folder check must come first."""
    from design.api import RUNNERS
    from design.reproduce import report as reproduce
    from design.tradeoff import run as tradeoff

    for kind in RUNNERS:
        monkeypatch.setitem(RUNNERS, kind, _must_not_run)
    for kind in tradeoff.STUDIES:
        monkeypatch.setitem(tradeoff.STUDIES, kind, _must_not_run)
    monkeypatch.setattr(reproduce, "compute_sections", _must_not_run)


COMMANDS = {"simulate": ["simulate", str(ROOT / "problems" / "beam_table_2_1.yaml")],
            "solve": ["solve", str(ROOT / "problems" / "hold_time.yaml")],
            "tradeoff": ["tradeoff", str(ROOT / "problems" / "beam_table_2_1.yaml")],
            "reproduce": ["reproduce"]}


@pytest.mark.parametrize("command", list(COMMANDS))
def test_an_output_folder_under_a_file_is_refused_before_the_run(tmp_path, capsys, nothing_runs,
                                                                  command):
    """Exit 2 naming the folder, before anything runs or is written."""
    blocker = tmp_path / "a_file"
    blocker.write_text("not a folder")
    out = blocker / "out"
    assert main([*COMMANDS[command], "--out", str(out), "--quiet"]) == 2
    assert capsys.readouterr().err == (f"error: output folder '{out}' cannot be created: "
                                       f"'{blocker}' is a file. Nothing was written.\n")
    assert [p.name for p in tmp_path.iterdir()] == ["a_file"]
    assert blocker.read_text() == "not a folder"


@pytest.mark.skipif(os.geteuid() == 0, reason="root writes to read-only folders")
@pytest.mark.parametrize("command", list(COMMANDS))
def test_a_read_only_output_folder_is_refused_before_the_run(tmp_path, capsys, nothing_runs,
                                                             command):
    locked = tmp_path / "locked"
    locked.mkdir()
    locked.chmod(0o555)
    try:
        assert main([*COMMANDS[command], "--out", str(locked / "out"), "--quiet"]) == 2
        err = capsys.readouterr().err
        assert f"output folder '{locked / 'out'}' cannot be written to: Permission denied" in err
        assert not any(locked.iterdir())
    finally:
        locked.chmod(0o755)


def test_the_api_checks_its_output_folder_before_the_run(tmp_path, nothing_runs):
    from design.io.results import OutputFolderError

    blocker = tmp_path / "a_file"
    blocker.write_text("")
    with pytest.raises(OutputFolderError, match="is a file"):
        design.simulate(ROOT / "problems" / "beam_table_2_1.yaml", out=blocker / "out")


@pytest.mark.skipif(not Path("/proc/self").is_dir(), reason="needs Linux's /proc")
def test_an_output_folder_where_no_file_can_be_made_is_refused(capsys, nothing_runs):
    """/proc takes no new files, not even from root."""
    assert main([*COMMANDS["simulate"], "--out", "/proc/design-out", "--quiet"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: output folder '/proc/design-out' cannot be written to: ")
    assert err.endswith("(creating a file in '/proc'). Nothing was written.\n")


def test_reusing_an_output_folder_leaves_only_the_new_runs_files(tmp_path, capsys):
    """A contact scene run into a beam scene's folder
    removes the beam's shapes.csv and figure; a file the toolkit did not
    write stays."""
    out = tmp_path / "out"
    assert main(["simulate", str(ROOT / "problems" / "beam_table_2_1.yaml"), "--out", str(out),
                 "--quiet"]) == 0
    assert (out / "shapes.csv").is_file() and (out / "figures" / "deflection.png").is_file()
    (out / "notes.txt").write_text("mine")
    capsys.readouterr()
    assert main(["simulate", str(ROOT / "problems" / "contact_case1.yaml"), "--out", str(out),
                 "--quiet"]) == 0
    *written, verdict = capsys.readouterr().out.splitlines()
    assert verdict == "finished: every case converged"
    assert sorted(str(p) for p in out.rglob("*") if p.is_file()) == sorted(
        [*written, str(out / "notes.txt"), str(out / ".design-outputs")])
    assert json.loads((out / "result.json").read_text())["kind"] == "contact"
    assert (out / ".design-outputs").read_text().split() == [
        str(Path(p).relative_to(out).as_posix()) for p in written]


def test_a_manifest_never_removes_files_outside_its_folder(tmp_path):
    from design.io.results import MANIFEST, record_outputs

    out, outside = tmp_path / "out", tmp_path / "outside.txt"
    out.mkdir()
    outside.write_text("keep")
    (out / "old.csv").write_text("")
    (out / MANIFEST).write_text(f"old.csv\n../outside.txt\n{outside}\n{MANIFEST}\n")
    (out / "new.csv").write_text("")
    assert record_outputs(out, [out / "new.csv"]) == [out / "old.csv"]
    assert outside.read_text() == "keep" and not (out / "old.csv").exists()
    assert (out / MANIFEST).read_text() == "new.csv\n"


def _footer_command(report: Path) -> str:
    text = report.read_text()
    return text[text.index("Command: ") + len("Command: "):].split("</p>")[0]


def test_the_report_gives_the_command_that_reruns_its_scene_file(tmp_path, monkeypatch):
    """The footer names the scene file as it was given (not
    `<name>.yaml`, which need not exist), so the command works where the run did."""
    monkeypatch.chdir(ROOT)
    scene = tmp_path / "my scene.yaml"
    scene.write_text((ROOT / "problems" / "beam_table_2_1.yaml").read_text())  # name: beam_table_2_1
    out = tmp_path / "out"
    assert main(["simulate", str(scene), "--out", str(out), "--quiet"]) == 0
    assert json.loads((out / "result.json").read_text())["scene_file"] == str(scene)
    assert _footer_command(out / "report.html") == f"design simulate {scene}"
    assert main(["simulate", "problems/contact_case1.yaml", "--out", str(out), "--quiet"]) == 0
    command = _footer_command(out / "report.html").split()
    assert command == ["design", "simulate", "problems/contact_case1.yaml"]
    assert main(["check", command[2]]) == 0                       # from the checkout root


def test_a_design_reports_footer_says_design_solve():
    from design.report.grasp import reproduce_section
    from design.report.page import Page

    page = Page("t")
    reproduce_section(page, {"kind": "design", "toolkit_version": "0", "scene_file":
                             "problems/hold_time.yaml"}, [], 1.0)
    assert "Command: design solve problems/hold_time.yaml</p>" in page.render()


def test_a_scene_given_as_content_has_no_command(tmp_path):
    scene = {"kind": "beam", "finger": {"length": 0.2, "EI": 0.08},
             "load": {"F": 15, "alpha": 1.5, "at": 0.1}}
    assert "scene_file" not in design.simulate(scene, out=tmp_path).to_dict()
    assert "The scene was given as content from Python, not as a file." in (
        tmp_path / "report.html").read_text()


def test_beam_shape_is_the_whole_finger_and_tip_is_the_load_point(tmp_path):
    """`tip` is the load point (s = at); `shape` runs on to
    the finger's free end, straight and moment-free past the load."""
    import numpy as np
    import yaml

    result = design.simulate(ROOT / "problems" / "beam_table_2_3.yaml", out=tmp_path).to_dict()
    length, case = result["finger"]["length"], result["cases"][0]
    shape = {k: np.array(v) for k, v in case["shape"].items()}
    assert case["at"] < length and shape["s"][-1] == length
    at = int(np.flatnonzero(shape["s"] == case["at"])[0])
    assert [shape[k][at] for k in ("x", "y", "psi")] == [case["tip"][k] for k in ("x", "y", "psi")]
    beyond = slice(at, None)
    np.testing.assert_array_equal(shape["psi"][beyond], case["tip"]["psi"])
    np.testing.assert_allclose(shape["M"][beyond], 0.0, atol=1e-12)
    run = np.hypot(shape["x"][-1] - shape["x"][at], shape["y"][-1] - shape["y"][at])
    assert run == pytest.approx(length - case["at"], rel=1e-12)
    rows = list(csv.DictReader((tmp_path / "shapes.csv").open()))
    assert float(rows[-1]["s_m"]) == pytest.approx(length)
    scene = yaml.safe_load((ROOT / "problems" / "beam_table_2_3.yaml").read_text())
    at_the_end = design.simulate({**scene, "load": {"F": 15, "alpha": "90 deg"}}
                                 ).to_dict()["cases"][0]
    assert at_the_end["shape"]["s"][-1] == at_the_end["at"] == length
    assert at_the_end["shape"]["x"][-1] == at_the_end["tip"]["x"]
