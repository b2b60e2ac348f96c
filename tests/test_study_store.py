"""The case store: its schema and WAL journal as documented, and the
stores it refuses (another problem's, an earlier run's without resume,
a file that is no store), leaving them as they were."""

import functools
import re
import sqlite3
from datetime import datetime, timezone
from pathlib import Path

import pytest

import design
from design.errors import StudyError
from design.study import Case, StudyOptions, run_study
from design.study import store as store_module
from design.study.store import read_cases
from tests.study_tasks import called, value

ROOT = Path(__file__).resolve().parents[1]
CASES = [Case("a", {"x": 1}), Case("b", {"x": 2}, after="a")]


def documented_schema(text: str) -> dict[str, list[str]]:
    """The tables and columns of the schema block in ``text``: lines
    ``study(name TYPE ...`` / ``cases(name TYPE`` and the column lines after them."""
    tables, table = {}, None
    for line in text.splitlines():
        m = re.match(r"\s*(?:(study|cases)\()?\s*(\w+) (INTEGER|TEXT|REAL)\b", line)
        if not m:
            table = None if not line.strip() or line.strip().startswith("```") else table
            continue
        if m.group(1):
            table = m.group(1)
            tables[table] = []
        if table:
            tables[table].append(m.group(2))
    return tables


def run(store: Path, digest: str = "digest-1", resume: bool = False, cases=CASES) -> dict:
    calls = store.parent / "calls"
    calls.mkdir(exist_ok=True)
    return run_study(cases, functools.partial(value, calls), label="study of t",
                     options=StudyOptions(workers=1, store=store, resume=resume),
                     problem_digest=digest)


def test_the_store_has_the_documented_tables_in_wal_mode(tmp_path):
    store = tmp_path / "cases.sqlite"
    run(store)
    db = sqlite3.connect(store)
    try:
        assert db.execute("PRAGMA journal_mode").fetchone()[0] == "wal"
        actual = {table: [row[1] for row in db.execute(f"PRAGMA table_info({table})")]
                  for table in ("study", "cases")}
        digest, label, version, created = db.execute(
            "SELECT problem_digest, label, version, created_at FROM study").fetchone()
        key_is_primary = [row[5] for row in db.execute("PRAGMA table_info(cases)")][0]
    finally:
        db.close()
    guide = (ROOT / "docs" / "guide.md").read_text(encoding="utf-8")
    studies = guide[guide.index("## Studies: workers and resume"):]
    assert documented_schema(store_module.__doc__) == actual
    assert documented_schema(studies[:studies.index("\n## ", 5)]) == actual
    assert actual["cases"][:1] == ["key"] and key_is_primary == 1
    assert (digest, label, version) == ("digest-1", "study of t", design.__version__)
    age = datetime.now(timezone.utc) - datetime.fromisoformat(created)
    assert 0 <= age.total_seconds() < 60


def test_an_unfinished_store_is_refused_without_resume(tmp_path):
    store = tmp_path / "cases.sqlite"
    failing = [CASES[0], Case("b", {"x": 2, "fail": True}, after="a")]
    run(store, cases=failing)                       # b fails: the study is not completed
    before = [row["finished_at"] for row in read_cases(store)]
    with pytest.raises(StudyError) as refused:
        run(store)
    assert str(store) in str(refused.value) and "--resume" in str(refused.value)
    assert "unfinished" in str(refused.value) and "delete the file" in str(refused.value)
    assert [row["finished_at"] for row in read_cases(store)] == before
    assert called(tmp_path / "calls") == ["a", "b"]


def test_a_completed_store_is_started_again_without_resume(tmp_path):
    store = tmp_path / "cases.sqlite"
    run(store)
    run(store)                                      # a new run replaces a completed study
    assert called(tmp_path / "calls") == ["a", "a", "b", "b"]
    assert [row["key"] for row in read_cases(store)] == ["a", "b"]
    run(store, resume=True)                         # resumed: nothing runs again
    assert len(called(tmp_path / "calls")) == 4


def test_another_problems_store_is_refused_on_resume(tmp_path):
    store = tmp_path / "cases.sqlite"
    run(store, digest="digest-1")
    with pytest.raises(StudyError) as refused:
        run(store, digest="digest-2", resume=True)
    assert str(store) in str(refused.value) and "problem changed" in str(refused.value)
    assert isinstance(refused.value, ValueError)
    assert len(list((tmp_path / "calls").iterdir())) == 2        # nothing ran again
    assert run(store, digest="digest-1", resume=True)["b"]["chain"] == ["a", "b"]


def test_a_store_without_cases_is_started_again(tmp_path):
    store = tmp_path / "cases.sqlite"
    run(store, digest="digest-1", cases=[])
    assert run(store, digest="digest-2")["b"]["status"] == "verified"
    db = sqlite3.connect(store)
    assert db.execute("SELECT problem_digest FROM study").fetchone()[0] == "digest-2"
    db.close()


def test_a_file_that_is_no_store_is_refused_and_left_alone(tmp_path):
    store = tmp_path / "cases.sqlite"
    store.write_text("not a database")
    with pytest.raises(StudyError, match="is not a case store"):
        run(store, resume=True)
    assert store.read_text() == "not a database"
