"""Output shared by the validation studies: one JSON file of rows, written whole."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from design.io.files import TOOLKIT_ROOT


def parser(doc: str, name: str) -> argparse.ArgumentParser:
    """A study's command line: described by its docstring's first line, with
    ``--out DIR`` (default reports/<name>/)."""
    p = argparse.ArgumentParser(description=doc.splitlines()[0])
    p.add_argument("--out", type=Path, default=TOOLKIT_ROOT / "reports" / name)
    return p


def write_rows(path: Path, rows: list[dict], wall_time_s: float, **extra) -> None:
    """``rows`` (SI units) and the study's wall time to ``path``, through a
    temporary file so that an interrupted study leaves no partial file."""
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(".tmp")
    tmp.write_text(json.dumps({"units": {"force": "N", "length": "m", "time": "s",
                                         "angle": "deg"},
                               "wall_time_s": wall_time_s, **extra, "rows": rows}, indent=1))
    tmp.replace(path)
    print(f"wrote {path}")
