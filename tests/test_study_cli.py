"""`design solve --workers/--scheduler/--resume` and `design.api.solve`'s
keywords reach the design runner as StudyOptions; bad values and an earlier
run's store are refused before the run; `design cases` lists a store."""

import functools
import json
from pathlib import Path

import pytest

from design.api import RUNNERS, solve
from design.cli import main
from design.errors import StudyError
from design.io.design_problem import DesignProblem
from design.study import Case, StudyOptions, run_study
from tests.study_tasks import value

ROOT = Path(__file__).resolve().parents[1]
PROBLEM = ROOT / "problems" / "hold_time.yaml"


class Stop(Exception):
    """Raised by the stand-in runner once it has the study options."""


@pytest.fixture
def runner(monkeypatch) -> list:
    """The design runner replaced by one that records its ``study`` and stops."""
    seen = []

    def record(problem, progress, study=None):
        seen.append(study)
        raise Stop

    monkeypatch.setitem(RUNNERS, DesignProblem, record)
    return seen


def stored(out: Path) -> Path:
    """A case store in ``out`` with two finished cases and a failed one."""
    (out / "calls").mkdir(parents=True)
    run_study([Case("start-01", {"x": 3}), Case("start-02", {"x": 4}, after="start-01"),
               Case("start-03", {"x": 1, "fail": True})],
              functools.partial(value, out / "calls"), label="t",
              options=StudyOptions(workers=1, store=out / "cases.sqlite"))
    return out / "cases.sqlite"


def test_the_flags_reach_the_runner_as_study_options(tmp_path, runner):
    out = tmp_path / "out"
    with pytest.raises(Stop):
        main(["solve", str(PROBLEM), "--out", str(out), "--quiet", "--workers", "3",
              "--scheduler", "tcp://localhost:8786", "--resume"])
    with pytest.raises(Stop):
        main(["solve", str(PROBLEM), "--out", str(out), "--quiet"])
    assert runner == [StudyOptions(workers=3, scheduler="tcp://localhost:8786", resume=True,
                                   store=out / "cases.sqlite"),
                      StudyOptions(store=out / "cases.sqlite")]


def test_the_api_keywords_reach_the_runner(tmp_path, runner):
    with pytest.raises(Stop):
        solve(PROBLEM, out=tmp_path, workers=1, resume=True)
    with pytest.raises(Stop):
        solve(PROBLEM)
    assert runner == [StudyOptions(workers=1, resume=True, store=tmp_path / "cases.sqlite"),
                      StudyOptions()]
    with pytest.raises(ValueError, match="workers: an integer >= 1"):
        solve(PROBLEM, workers=0)
    with pytest.raises(ValueError, match="resume needs a case store"):
        solve(PROBLEM, resume=True)
    assert len(runner) == 2


@pytest.mark.parametrize("flag, value, expected", [
    ("--workers", "0", "argument --workers: an integer >= 1"),
    ("--workers", "two", "argument --workers: an integer >= 1"),
    ("--scheduler", "localhost", "argument --scheduler: a Dask scheduler's address"),
])
def test_bad_flags_exit_2_and_write_nothing(tmp_path, capsys, runner, flag, value, expected):
    with pytest.raises(SystemExit) as exited:
        main(["solve", str(PROBLEM), "--out", str(tmp_path / "out"), flag, value])
    assert exited.value.code == 2
    err = capsys.readouterr().err
    assert expected in err and "Nothing was written" in err
    assert runner == [] and not (tmp_path / "out").exists()


def test_an_earlier_runs_store_is_refused_before_the_run_unless_resumed(tmp_path, capsys,
                                                                         runner):
    store = stored(tmp_path / "out")
    assert main(["solve", str(PROBLEM), "--out", str(tmp_path / "out"), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert f"error: {store} already holds 3 cases" in err and "--resume" in err
    assert runner == []
    with pytest.raises(StudyError, match="already holds 3 cases"):
        solve(PROBLEM, out=tmp_path / "out")
    with pytest.raises(Stop):
        main(["solve", str(PROBLEM), "--out", str(tmp_path / "out"), "--quiet", "--resume"])
    assert len(runner) == 1


def test_a_study_error_in_the_run_exits_2(tmp_path, capsys, monkeypatch):
    def refuse(problem, progress, study=None):
        raise StudyError(f"{study.store}: the problem changed since its cases were computed")

    monkeypatch.setitem(RUNNERS, DesignProblem, refuse)
    out = tmp_path / "out"
    assert main(["solve", str(PROBLEM), "--out", str(out), "--quiet", "--resume"]) == 2
    assert capsys.readouterr().err == (f"error: {out / 'cases.sqlite'}: the problem changed "
                                       f"since its cases were computed. Nothing was written.\n")
    assert not out.exists()


def test_design_cases_lists_a_store_given_by_path_or_by_problem(tmp_path, capsys,
                                                                monkeypatch):
    store = stored(tmp_path / "reports" / "hold_time")
    assert main(["cases", str(store), "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)
    assert [(r["key"], r["status"]) for r in rows] == [
        ("start-01", "verified"), ("start-02", "verified"), ("start-03", "error")]
    assert rows[1]["hold_time_s"] == pytest.approx(0.07)
    assert rows[1]["max_finger_force_N"] == 40.0
    assert rows[2]["message"] == "ValueError: case start-03 fails on purpose"
    assert set(rows[0]) == {"key", "status", "hold_time_s", "max_finger_force_N",
                            "wall_time_s", "worker", "finished_at"}
    assert main(["cases", str(store)]) == 0
    table = capsys.readouterr().out
    for text in ("start-02", "0.0700", "40.00", "peak (N)", "finished (UTC)", "fails on purpose"):
        assert text in table
    assert table.startswith(f"{store}: 3 cases\n")
    monkeypatch.chdir(tmp_path)                     # reports/<problem name>/ by default
    assert main(["cases", str(PROBLEM)]) == 0
    by_name = capsys.readouterr().out
    assert by_name.startswith("reports/hold_time/cases.sqlite: 3 cases\n")
    assert by_name.split("\n", 1)[1] == table.split("\n", 1)[1]
    assert main(["cases", str(PROBLEM), "--out", str(tmp_path / "reports" / "hold_time")]) == 0
    assert capsys.readouterr().out == table


def test_design_cases_without_a_store_exits_2(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(["cases", str(PROBLEM)]) == 2
    err = capsys.readouterr().err
    assert "error: no case store at reports/hold_time/cases.sqlite" in err
    (tmp_path / "junk.sqlite").write_bytes(b"SQLite format 3\x00" + b"\x00" * 100)
    assert main(["cases", str(tmp_path / "junk.sqlite")]) == 2
    assert "is not a case store" in capsys.readouterr().err
