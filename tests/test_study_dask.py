"""design.study on Dask: a LocalCluster of two worker processes returns what
the serial run returns, loses no case when a worker is killed, runs on a
running scheduler's workers, and stops cleanly on a real Ctrl-C."""

import functools
import io
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from design.study import Case, StudyOptions, StudyProgress, run_study
from design.study.store import read_cases
from tests.study_tasks import called, forked, value
from tests.test_study_engine import CASES, stripped, task

ROOT = Path(__file__).resolve().parents[1]
#: from Ctrl-C to the process's exit (s), as in test_interrupt.py
PROMPT = 3.0


@pytest.fixture(scope="module")
def serial(tmp_path_factory) -> dict:
    fn, _ = task(tmp_path_factory.mktemp("serial"))
    return stripped(run_study(CASES, fn, options=StudyOptions(workers=1), label="serial"))


def test_a_local_cluster_returns_the_serial_runs_results(tmp_path, serial, capsys):
    fn, calls = task(tmp_path)
    store = tmp_path / "cases.sqlite"
    results = run_study(CASES, fn, options=StudyOptions(workers=2, store=store), label="t",
                        progress=StudyProgress(stream=sys.stderr))
    assert stripped(results) == serial
    workers = {r["worker"] for r in results.values() if r["worker"]}
    assert workers and not any(w.endswith(f":{os.getpid()}") for w in workers)
    assert sorted(row["key"] for row in read_cases(store)) == sorted(serial)
    err = capsys.readouterr().err
    assert "running on 2 local worker processes" in err
    assert err.count("Traceback") == 1                     # the failing case's, once
    assert "WARNING" not in err and "distributed." not in err


def test_a_local_workers_case_may_fork_its_own_processes():
    """A case's pattern search simulates in two forked processes; a Dask
    worker that is a daemon may not have children, so the local workers
    are not daemons."""
    cases = [Case(f"x-{x}", {"x": x}) for x in (2, 3)]
    results = run_study(cases, forked, options=StudyOptions(workers=2), label="fork")
    assert [(r["status"], r["hold_time_s"], r["daemon"]) for r in results.values()] == \
        [("done", 8.0, False), ("done", 18.0, False)]


def test_a_killed_worker_loses_no_case(tmp_path, serial):
    """Case b1 kills its worker process on its first attempt: the nanny
    starts another, the scheduler runs b1 again, every case is stored.
    Results on the lost worker that a case still needs are computed again
    (a for b1, bad for after-bad); c, which no case needs, runs once."""
    calls = tmp_path / "calls"
    calls.mkdir()
    fn = functools.partial(value, calls, kill="b1", spare=os.getpid())
    store = tmp_path / "cases.sqlite"
    results = run_study(CASES, fn, options=StudyOptions(workers=2, store=store), label="t")
    assert (calls / "killed").exists()
    made = called(calls)
    assert made.count("b1") == 2 and made.count("c") == 1 and made.count("b2") == 1
    assert stripped(results) == serial
    assert sorted(row["key"] for row in read_cases(store)) == sorted(serial)


def test_a_running_scheduler_runs_the_cases(tmp_path, serial):
    from distributed import LocalCluster

    with LocalCluster(n_workers=1, threads_per_worker=1, processes=True,
                      dashboard_address=None) as cluster:
        shown = io.StringIO()
        fn, _ = task(tmp_path)
        results = run_study(CASES, fn, options=StudyOptions(scheduler=cluster.scheduler_address),
                            label="t", progress=StudyProgress(stream=shown))
    assert stripped(results) == serial
    assert f"the Dask scheduler at {cluster.scheduler_address} (1 workers now)" in shown.getvalue()


CHILD = """
import functools, sys
from pathlib import Path
from design import interrupt
from design.study import Case, StudyOptions, StudyProgress, run_study
from tests.study_tasks import value
folder = Path(sys.argv[1])
cases = [Case(f"c{i}", {"x": i, "sleep": 0.2}) for i in range(6)]
with interrupt.handled():
    try:
        run_study(cases, functools.partial(value, folder / "calls"), label="t",
                  options=StudyOptions(workers=2, store=folder / "cases.sqlite"),
                  progress=StudyProgress())
    except KeyboardInterrupt as exc:
        print(interrupt.stopped(exc), file=sys.stderr)
        sys.exit(130)
"""


def test_ctrl_c_stops_the_cluster_and_keeps_the_finished_cases(tmp_path, serial):
    """A real SIGINT to the whole process group, as a terminal sends it,
    while two workers run: the command exits 130 within PROMPT seconds,
    without a worker's traceback, the finished cases stored; resumed, the
    study runs only the others."""
    (tmp_path / "calls").mkdir()
    child = subprocess.Popen([sys.executable, "-c", CHILD, str(tmp_path)], cwd=ROOT, text=True,
                             stderr=subprocess.PIPE, start_new_session=True)
    lines = []
    try:
        for line in child.stderr:
            lines.append(line)
            if line.startswith("c0: verified") or line.startswith("c1: verified"):
                break
        else:
            pytest.fail("the study ended before its first case:\n" + "".join(lines))
        sent = time.monotonic()
        os.killpg(child.pid, signal.SIGINT)
        rest = child.communicate(timeout=30)[1]
        took = time.monotonic() - sent
    finally:
        if child.poll() is None:
            child.kill()
            child.wait()
    stderr = "".join(lines) + rest
    assert child.returncode == 130, stderr
    assert took < PROMPT, stderr
    assert "interrupted (Ctrl-C): stopped" in stderr
    assert "Traceback" not in stderr and "KeyboardInterrupt" not in stderr
    stored = [row["key"] for row in read_cases(tmp_path / "cases.sqlite")]
    assert 1 <= len(stored) < 6
    cases = [Case(f"c{i}", {"x": i, "sleep": 0.2}) for i in range(6)]
    fn, calls = task(tmp_path / "resumed")
    resumed = run_study(cases, fn, label="t", options=StudyOptions(
        workers=1, store=tmp_path / "cases.sqlite", resume=True))
    assert sorted(called(calls) + stored) == [f"c{i}" for i in range(6)]
    assert [resumed[f"c{i}"]["hold_time_s"] for i in range(6)] == [i / 100 for i in range(6)]
