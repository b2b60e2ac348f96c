"""What a study's LocalCluster costs: start and stop of the cluster that
``run_study`` starts (design/study/cluster.py: one worker process per core,
preloaded), and a whole study of 8 cases of 5 ms each on it against the
same cases in the process (``workers=1``). Each measured ``REPEAT`` times in
one process (Dask imported once, before the first), with the load average.

Prints the numbers and writes benchmarks/results/study.json.

    python -m benchmarks.study
"""

from __future__ import annotations

import functools
import json
import os
import statistics
import tempfile
import time
from pathlib import Path

from design.study import Case, StudyOptions, run_study
from design.study.cluster import dask_client
from tests.study_tasks import value

RESULTS = Path(__file__).parent / "results" / "study.json"
REPEAT = 5
CASES = [Case(f"c{i}", {"x": i}) for i in range(8)]


def timed(f) -> list[float]:
    out = []
    for _ in range(REPEAT):
        t0 = time.perf_counter()
        f()
        out.append(time.perf_counter() - t0)
    return out


def main() -> None:
    import distributed  # noqa: F401  imported once, as a command does once

    loadavg = [round(v, 2) for v in os.getloadavg()]
    options = StudyOptions()
    start, stop = [], []
    for _ in range(REPEAT):
        t0 = time.perf_counter()
        with dask_client(options, len(CASES)) as (client, where):
            t1 = time.perf_counter()
        start.append(t1 - t0)
        stop.append(time.perf_counter() - t1)
    with tempfile.TemporaryDirectory() as folder:
        task = functools.partial(value, Path(folder))
        cluster = timed(lambda: run_study(CASES, task, options=options, label="b"))
        serial = timed(lambda: run_study(CASES, task, options=StudyOptions(workers=1),
                                         label="b"))
    rows = {"cluster_start_s": start, "cluster_stop_s": stop, "study_8_cases_cluster_s": cluster,
            "study_8_cases_in_process_s": serial}
    result = {"cores": os.cpu_count(), "workers": where, "repeat": REPEAT,
              "loadavg": {"start": loadavg, "end": [round(v, 2) for v in os.getloadavg()]},
              **{name: {"median": statistics.median(v), "min": min(v), "max": max(v),
                        "all": v} for name, v in rows.items()}}
    for name, v in rows.items():
        print(f"{name:28s} median {statistics.median(v):.2f} s  ({min(v):.2f}-{max(v):.2f})")
    print(f"load average {result['loadavg']}")
    RESULTS.write_text(json.dumps(result, indent=1) + "\n")


if __name__ == "__main__":
    main()
