"""Output shared by the validation studies: one JSON file of rows, written whole."""

from __future__ import annotations

import json
from pathlib import Path


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
