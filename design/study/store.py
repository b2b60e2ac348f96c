"""The case store: every finished case of a study in one SQLite file
(``<out>/cases.sqlite``), written as each case finishes, so that a stopped
study loses no finished case and ``resume`` runs only the rest.

Schema (SQLite, WAL journal, so ``design cases`` can read while a study
writes)::

    study(id INTEGER PRIMARY KEY CHECK (id = 1),  -- one row
          problem_digest TEXT,   -- the caller's digest of the problem the cases belong to
          label TEXT,            -- the study's name in progress lines
          version TEXT,          -- design.__version__ that created the store
          created_at TEXT,       -- UTC, ISO 8601
          completed_at TEXT)     -- UTC, when every case finished without error; NULL before
    cases(key TEXT PRIMARY KEY,
          inputs TEXT,           -- the case's inputs, canonical JSON
          after TEXT,            -- the key of the case it needs, a JSON list of keys, or NULL
          result TEXT,           -- the result, JSON (with wall_time_s and worker)
          status TEXT,           -- result["status"]
          wall_time_s REAL,      -- the task's wall time (s), on its worker
          worker TEXT,           -- host:pid of the process that ran it; NULL if skipped
          finished_at TEXT)      -- UTC, ISO 8601

Only the process that coordinates the study writes (one writer; the
workers return their results to it). A stored case is reused only when its
key, inputs and ``after`` are the current ones and its status is neither
``error`` nor ``skipped``; a store whose problem digest is not the current
one is refused (:class:`~design.errors.StudyError`), never reused. Without
``resume``, a completed study's store is started again (like the run's
other files, a new run replaces it) and an unfinished one (stopped, or
with failed cases) is refused: its finished cases may be hours of work.
"""

from __future__ import annotations

import json
import sqlite3
from datetime import datetime, timezone
from pathlib import Path

from design import __version__
from design.errors import StudyError
from design.study.cases import FAILED, Case, canonical, case_row

#: the store's file name in a run's output folder
STORE = "cases.sqlite"

SCHEMA = """
CREATE TABLE IF NOT EXISTS study (id INTEGER PRIMARY KEY CHECK (id = 1),
    problem_digest TEXT NOT NULL, label TEXT NOT NULL, version TEXT NOT NULL,
    created_at TEXT NOT NULL, completed_at TEXT);
CREATE TABLE IF NOT EXISTS cases (key TEXT PRIMARY KEY, inputs TEXT NOT NULL, after TEXT,
    result TEXT NOT NULL, status TEXT NOT NULL, wall_time_s REAL, worker TEXT,
    finished_at TEXT NOT NULL);
"""


def utc_now() -> str:
    return datetime.now(timezone.utc).isoformat(timespec="seconds")


class CaseStore:
    """An open case store (use :func:`open_store`)."""

    def __init__(self, path: Path, connection: sqlite3.Connection):
        self.path, self._db = path, connection

    def finished(self, cases: list[Case]) -> dict[str, dict]:
        """The stored results that still hold for ``cases`` (in order: each
        after the case it needs), by key: same key, inputs and ``after``,
        not failed, and the case it needs reused too."""
        stored = {key: (inputs, after, json.loads(result)) for key, inputs, after, result in
                  self._db.execute("SELECT key, inputs, after, result FROM cases "
                                   "WHERE status NOT IN (?, ?)", FAILED)}
        reused: dict[str, dict] = {}
        for case in cases:
            inputs, after, result = stored.get(case.key, (None, None, None))
            if inputs == canonical(case.inputs) and after == case.after_text and \
                    all(need in reused for need in case.needs):
                reused[case.key] = result
        return reused

    def record(self, case: Case, result: dict) -> None:
        """Store a finished case (replacing an earlier attempt's), committed at once."""
        with self._db:
            self._db.execute("INSERT OR REPLACE INTO cases VALUES (?, ?, ?, ?, ?, ?, ?, ?)",
                             (case.key, canonical(case.inputs), case.after_text, canonical(result),
                              result["status"], result.get("wall_time_s"),
                              result.get("worker"), utc_now()))

    def complete(self) -> None:
        """Mark the study completed: every case finished without error."""
        with self._db:
            self._db.execute("UPDATE study SET completed_at = ?", (utc_now(),))

    def close(self) -> None:
        self._db.close()


def open_store(path: Path, problem_digest: str, label: str, resume: bool) -> CaseStore:
    """Open the store at ``path`` for a study, creating it if need be.

    Raises :class:`StudyError`, leaving the file as it was, if it is not a
    case store, if it holds cases and ``resume`` is false, or, resuming, if
    its problem digest is not ``problem_digest``.
    """
    path = Path(path)
    db = _connect(path)
    try:
        count = _count(db, path, resume)
        if count and not resume:                 # a completed study: start again
            with db:
                db.execute("DELETE FROM cases")
            count = 0
        stored = db.execute("SELECT problem_digest FROM study").fetchone()
        if count and stored[0] != problem_digest:
            raise StudyError(f"{path}: the problem changed since its cases were computed "
                             f"(problem digest {stored[0][:12]} there, {problem_digest[:12]} "
                             f"now); delete the file, or choose another output folder")
        if not count:
            with db:
                db.execute("INSERT OR REPLACE INTO study VALUES (1, ?, ?, ?, ?, NULL)",
                           (problem_digest, label, __version__, utc_now()))
    except BaseException:
        db.close()
        raise
    return CaseStore(path, db)


def check_store(path: Path, resume: bool) -> None:
    """Refuse, before a run starts, a store at ``path`` that :func:`open_store`
    would refuse whatever the problem (not a case store; an unfinished
    study's cases and no ``resume``). A missing file is fine (it is not
    made here)."""
    path = Path(path)
    if path.is_file():
        db = _connect(path)
        try:
            _count(db, path, resume)
        finally:
            db.close()


def _count(db: sqlite3.Connection, path: Path, resume: bool) -> int:
    """The number of stored cases; StudyError if there are some, the study
    is not completed and ``resume`` is false."""
    count = db.execute("SELECT count(*) FROM cases").fetchone()[0]
    completed = db.execute("SELECT completed_at FROM study").fetchone()
    if count and not resume and not (completed and completed[0]):
        raise StudyError(f"{path} already holds {count} case{'s' if count != 1 else ''} "
                         f"of an unfinished earlier run; pass --resume (resume=True) to reuse them, "
                         f"or delete the file to start again")
    return count


def read_cases(path: Path) -> list[dict]:
    """Every stored case of the store at ``path`` in the order they finished,
    as :func:`~design.study.cases.case_row` rows with ``finished_at`` (UTC)."""
    path = Path(path)
    if not path.is_file():
        raise StudyError(f"no case store at {path}")
    db = _connect(path)
    try:
        return [{**case_row(key, json.loads(result)), "finished_at": finished}
                for key, result, finished in db.execute(
                    "SELECT key, result, finished_at FROM cases ORDER BY finished_at, rowid")]
    finally:
        db.close()


def _connect(path: Path) -> sqlite3.Connection:
    """A connection to the store at ``path``, made (WAL journal, the
    schema) if there is no file; StudyError if the file is not a case store."""
    new = not path.exists() or path.stat().st_size == 0
    if new:
        path.parent.mkdir(parents=True, exist_ok=True)
    db = sqlite3.connect(path)
    try:
        if new:
            db.execute("PRAGMA journal_mode=WAL")
            db.executescript(SCHEMA)
        db.execute("SELECT problem_digest, label, version, created_at FROM study").fetchall()
        db.execute("SELECT key, inputs, after, result, status, wall_time_s, worker, "
                   "finished_at FROM cases LIMIT 1").fetchall()
    except sqlite3.DatabaseError as exc:
        db.close()
        raise StudyError(f"{path} is not a case store ({exc})") from None
    return db
