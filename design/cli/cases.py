"""``design cases PROBLEM_OR_DB``: the cases a study stored, as a table
(key, status, hold, peak, wall time, worker, finished_at; the message of a
failed case) or, with ``--json``, as JSON rows. Given a design problem, the
store is ``cases.sqlite`` in its output folder (``--out``, default
reports/<name>/). Exit status: 0 listed; 2 no store there, or not a store."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from design.cli.common import EXIT_BAD_INPUT, EXIT_OK, default_folder, report_problems
from design.errors import ProblemFileError, StudyError
from design.study.progress import case_table, console
from design.study.store import STORE, read_cases

#: the first bytes of every SQLite database file
SQLITE_HEADER = b"SQLite format 3\x00"


def cmd_cases(args: argparse.Namespace) -> int:
    source = Path(args.source)
    if args.out:
        path = Path(args.out) / STORE
    elif _is_sqlite(source):
        path = source
    else:
        from design.io.scene import load_scene

        try:
            path = default_folder(load_scene(args.source), args.source) / STORE
        except ProblemFileError as exc:
            return report_problems(exc)
    if not path.is_file():
        print(f"error: no case store at {path}: 'design solve' writes it there as the "
              f"problem's cases finish (--out names another output folder)", file=sys.stderr)
        return EXIT_BAD_INPUT
    try:
        rows = read_cases(path)
    except StudyError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    if args.json:
        print(json.dumps(rows, indent=1))
    else:
        console(sys.stdout).print(case_table(rows, title=f"{path}: {len(rows)} cases"))
    return EXIT_OK


def _is_sqlite(path: Path) -> bool:
    try:
        with path.open("rb") as fh:
            return fh.read(len(SQLITE_HEADER)) == SQLITE_HEADER
    except OSError:
        return False
