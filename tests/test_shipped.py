"""The shipped problems and models as a user finds them:
bare problem names resolve from any folder, `design examples` lists them,
and a built (non-editable) install carries them as package data."""

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

from design.cli import main
from design.io.files import PROBLEMS, TOOLKIT_ROOT

ROOT = Path(__file__).resolve().parents[1]
SHIPPED = sorted(p.name for p in (ROOT / "problems").glob("*.yaml"))


def test_in_a_checkout_the_shipped_files_are_the_checkouts():
    assert TOOLKIT_ROOT == ROOT and PROBLEMS == ROOT / "problems"


@pytest.mark.parametrize("name", ["hold_time.yaml", "hold_time", "beam_table_2_3.yaml"])
def test_a_bare_problem_name_resolves_from_any_folder(tmp_path, monkeypatch, capsys, name):
    monkeypatch.chdir(tmp_path)
    assert main(["check", name]) == 0
    assert capsys.readouterr().out == f"{name}: OK\n"


def test_the_working_folder_comes_before_the_shipped_problems(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    Path("beam_table_2_3.yaml").write_text("kind: beam\nfinger: {length: -1, EI: 0.08}\n")
    assert main(["simulate", "beam_table_2_3.yaml", "--out", "out"]) == 2
    assert "beam_table_2_3.yaml: finger.length: -1 m is outside" in capsys.readouterr().err
    assert not Path("out").exists()


def test_simulate_runs_a_shipped_problem_by_name(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(["simulate", "beam_table_2_1.yaml", "--quiet"]) == 0
    assert (tmp_path / "reports" / "beam_table_2_1" / "result.json").is_file()


def test_a_misspelt_bare_name_says_where_it_looked(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(["simulate", "hold_tim.yaml", "--out", "out"]) == 2
    err = capsys.readouterr().err
    assert (f"error: hold_tim.yaml: no such file in {tmp_path} nor among the shipped problems "
            f"({ROOT / 'problems'}; 'design examples' lists them); did you mean "
            f"'hold_time.yaml'?\n") in err
    assert not Path("out").exists()


def test_examples_lists_every_shipped_problem_with_the_command_that_runs_it(capsys):
    assert main(["examples"]) == 0
    out = capsys.readouterr().out
    for name in SHIPPED:
        data = yaml.safe_load((ROOT / "problems" / name).read_text())
        command = "solve" if data["kind"] == "design" else "simulate"
        first = " ".join(data["description"].split()).split(". ")[0]
        assert f"  design {command} {name}\n      {first}" in out


def test_a_built_install_carries_the_models_and_problems(tmp_path):
    """setup.py's build (what `pip install .` installs) puts models/ and
    problems/ inside the package, and the toolkit built that way, run from
    an unrelated folder, finds them (no checkout beside it)."""
    source, lib, elsewhere = tmp_path / "source", tmp_path / "lib", tmp_path / "elsewhere"
    for part in ["design", "models", "problems"]:
        shutil.copytree(ROOT / part, source / part,
                        ignore=shutil.ignore_patterns("__pycache__"))
    for part in ["setup.py", "pyproject.toml", "README.md"]:
        shutil.copy(ROOT / part, source / part)
    subprocess.run([sys.executable, "setup.py", "-q", "build_py", "--build-lib", str(lib)],
                   cwd=source, check=True, capture_output=True, timeout=120)
    shipped = lib / "design" / "shipped"
    assert sorted(p.relative_to(shipped).as_posix() for p in shipped.rglob("*.yaml")) == sorted(
        p.relative_to(ROOT).as_posix() for p in [*ROOT.glob("models/**/*.yaml"),
                                                 *ROOT.glob("problems/*.yaml")])
    elsewhere.mkdir()
    env = {**os.environ, "PYTHONPATH": str(lib)}
    done = subprocess.run(
        [sys.executable, "-c", "import sys, design, design.cli; print(design.__file__); "
         "sys.exit(design.cli.main(['simulate', 'beam_table_2_3.yaml', '--out', 'out', "
         "'--quiet']))"], cwd=elsewhere, env=env, capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert done.stdout.splitlines()[0] == str(lib / "design" / "__init__.py")
    assert (elsewhere / "out" / "result.json").is_file()
