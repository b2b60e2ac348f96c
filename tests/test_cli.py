"""design simulate / design check and the Python API, as a user runs them."""

import csv
import json
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
    api = jsonable(design.simulate(scene))
    assert written.pop("solve_time_s") > 0 and api.pop("solve_time_s") > 0
    assert written == api
    case = written["cases"][0]
    for key in ["F", "alpha", "at", "tip", "shape", "error_estimate", "converged", "branch"]:
        assert key in case
    assert set(case["shape"]) >= {"s", "x", "y", "psi"}
    assert written["kind"] == "beam"
    assert case["converged"] and case["error_estimate"] < 1e-8
    rows = list(csv.DictReader((out / "cases.csv").open()))
    assert float(rows[0]["tip_y_m"]) == pytest.approx(case["tip"]["y"])


def test_sweep_result_has_one_case_per_load(tmp_path):
    result = design.simulate(ROOT / "problems" / "beam_sweep.yaml", out=tmp_path)
    forces = [c["F"] for c in result["cases"]]
    assert forces == [0, 2.5, 5, 7.5, 10, 12.5, 15, 17.5, 20, 22.5, 25, 27.5, 30]
    assert result["cases"][0]["branch"] == "straight"
    assert all(c["branch"] == "primary" for c in result["cases"][1:])


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


def test_the_documented_api_is_callable_and_the_version_is_shown(capsys):
    """README's Python calls exist as documented (`from design.api import
    solve`, `design.simulate`, `design.check`); `design --version` prints the
    package's version."""
    import design
    from design.api import solve
    readme = (Path(__file__).resolve().parents[1] / "README.md").read_text()
    assert "from design.api import solve" in readme and "design.solve(" not in readme
    assert callable(solve) and callable(design.simulate) and callable(design.check)
    assert "os" not in dir(design)
    with pytest.raises(SystemExit) as exit_:
        main(["--version"])
    assert exit_.value.code == 0 and capsys.readouterr().out.strip() == f"design {design.__version__}"
