"""An 8-case design study with 1 and with 2 worker processes: the wall
time of `design solve` on a multistart of problems/hold_time.yaml (the
baseline and 7 Sobol starts, seed 0), shortened so that the pair runs in
minutes (one outer iteration of at most 20 Ipopt iterations per start),
through the API with ``workers=1`` (in the process, one case after
another) and ``workers=2`` (a LocalCluster), in that order, in one run.
The two must give the same cases (status, verified hold and peak to the
last digit: the loop is deterministic and limited by iterations, not
time). Both runs compile nothing: the compiled functions are built before
the first, so neither pays for gcc.

The speed-up is bounded by what only the coordinating process does
(setup, the baseline's 4x finer verification, result and report) and by
the longest case: both are recorded.

Prints the table and writes benchmarks/results/study_solve.json with the
cores, the load average at the start and end, and the speed-up.

    python -m benchmarks.study_solve
"""

from __future__ import annotations

import json
import os
import tempfile
import time
from pathlib import Path

import yaml

from design.api import solve
from design.solvers.optimize.profile import STUDY
from design.study.store import STORE, read_cases

ROOT = Path(__file__).resolve().parents[1]
RESULTS = Path(__file__).parent / "results" / "study_solve.json"


def problem(folder: Path) -> Path:
    """hold_time.yaml as an 8-start multistart of one short outer iteration."""
    data = yaml.safe_load((ROOT / "problems" / "hold_time.yaml").read_text())
    data.update(name="study_8_cases", scene=str(ROOT / "problems" / data["scene"]),
                multistart={"starts": 8, "seed": 0})
    data["solver"].update(outer_iterations=1, max_iter=20)
    path = folder / "study_8_cases.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


def cases(out: Path) -> dict:
    result = json.loads((out / "result.json").read_text())
    return {r["case"]: (r["status"], r["verified_hold_time_s"], r["verified_max_finger_force_N"])
            for r in result["multistart"]["starts"]}


def outside_the_study(out: Path) -> float | None:
    """The wall time (s) the coordinating process spent outside the cases
    (setup, the baseline's verification, result), for a run on workers
    (whose profile has the cases as one phase); None in the process."""
    profile = json.loads((out / "result.json").read_text())["profile"]
    study = [p["wall_time_s"] for p in profile["phases"] if p["phase"] == STUDY]
    return profile["wall_time_s"] - study[0] if study else None


def main() -> None:
    loadavg = [round(v, 2) for v in os.getloadavg()]
    with tempfile.TemporaryDirectory() as folder:
        path = problem(Path(folder))
        rows, outcomes = [], {}
        for workers in (1, 2):
            out = Path(folder) / f"workers_{workers}"
            t0, cpu = time.perf_counter(), time.process_time()
            result = solve(path, out, workers=workers).to_dict()
            wall = time.perf_counter() - t0
            outcomes[workers] = cases(out)
            case_times = [row["wall_time_s"] for row in read_cases(out / STORE)]
            rows.append({"workers": workers, "wall_time_s": wall,
                         "case_wall_times_s": case_times,
                         "outside_the_study_s": outside_the_study(out),
                         "coordinator_cpu_s": time.process_time() - cpu,
                         "status": result["status"],
                         "best_verified_hold_s": result["verification"]["hold_time_s"]})
            print(f"workers {workers}: {wall:7.1f} s wall, status {result['status']}, best "
                  f"verified hold {result['verification']['hold_time_s']:.4f} s; cases "
                  f"{sum(case_times):.1f} s in all, longest {max(case_times):.1f} s", flush=True)
    same = outcomes[1] == outcomes[2]
    speedup = rows[0]["wall_time_s"] / rows[1]["wall_time_s"]
    print(f"2 workers: {rows[1]['outside_the_study_s']:.1f} s of the run outside the cases")
    report = {"cores": os.cpu_count(),
              "loadavg": {"start": loadavg, "end": [round(v, 2) for v in os.getloadavg()]},
              "rows": rows, "speedup_2_workers": speedup, "same_cases": same,
              "cases": {k: list(v) for k, v in outcomes[1].items()}}
    RESULTS.write_text(json.dumps(report, indent=2) + "\n")
    print(f"speed-up with 2 workers: {speedup:.2f}x; the same cases: {same}")
    print(f"load average {loadavg} at the start; written {RESULTS}")


if __name__ == "__main__":
    main()
