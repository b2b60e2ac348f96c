"""Writing a benchmark's JSON result (benchmarks/results/, tracked), stamped
with the date it was measured (``measured_at``, UTC, read by
benchmarks/pages.py)."""

from __future__ import annotations

import json
import os
import platform
from datetime import datetime, timezone
from pathlib import Path

from design.io.results import jsonable


def cpu_model() -> str:
    """The processor's model name (Linux's /proc/cpuinfo; else what the
    platform says): machines of the same core count differ by 2-3x in the
    benchmarks' wall times."""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def machine(load_at_start: tuple[float, ...], at_end: bool = False) -> dict:
    """The ``machine`` entry of a result: Python, cores, the processor, the
    load averages at the start (given) and, with ``at_end``, now."""
    out = {"python": platform.python_version(), "cores": os.cpu_count(), "cpu": cpu_model(),
           "load_average_at_start": load_at_start}
    return {**out, "load_average_at_end": os.getloadavg()} if at_end else out


def write_results(path: Path, result: dict) -> None:
    """Write ``result`` as indented JSON to ``path`` (its folder made), with
    today's date as ``measured_at``, and say so."""
    path.parent.mkdir(parents=True, exist_ok=True)
    stamped = {"measured_at": datetime.now(timezone.utc).date().isoformat(), **result}
    path.write_text(json.dumps(jsonable(stamped), indent=1) + "\n")
    print(f"\nwrote {path}")
