"""Writing a benchmark's JSON result (benchmarks/results/, tracked)."""

from __future__ import annotations

import json
from pathlib import Path

from design.io.results import jsonable


def write_results(path: Path, result: dict) -> None:
    """Write ``result`` as indented JSON to ``path`` (its folder made) and say so."""
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(jsonable(result), indent=1) + "\n")
    print(f"\nwrote {path}")
