"""Simulations in forked processes, some run ahead (design/solvers/optimize/
ahead.py): what a call returns does not depend on what ran ahead; a job
run ahead is not run again when asked for; one no longer wanted is killed,
not waited for; a job's exception reaches the caller."""

import os
import subprocess
import sys
import time

import pytest

from design.solvers.optimize.ahead import Ahead
from design.solvers.optimize.forked import forked_map


def stamped(job):
    """The job, the process that ran it and when it began (monotonic s);
    a job ("sleep", s) first sleeps s seconds, ("fail", _) raises."""
    began = time.monotonic()
    kind, value = job
    if kind == "sleep":
        time.sleep(value)
    if kind == "fail":
        raise ValueError(f"job {value} failed")
    return job, os.getpid(), began


def key(job):
    return job


@pytest.fixture
def ahead(monkeypatch):
    """Two processes on a machine whose other processes leave a core free
    (whatever else the test run does)."""
    monkeypatch.setattr("design.solvers.optimize.ahead.others_running", lambda: 0)
    runner = Ahead(stamped, key, processes=2)
    yield runner
    runner.close()


def test_jobs_run_in_forked_processes_in_order(ahead):
    jobs = [("sleep", 0.05 * (3 - n)) for n in range(3)]
    values = ahead.run(jobs)
    assert [v[0] for v in values] == jobs
    pids = {v[1] for v in values}
    assert len(pids) == 3 and os.getpid() not in pids


def test_a_job_run_ahead_is_used_when_asked_for_not_run_again(ahead):
    """While a slow job runs, the free core starts the job asked for next;
    the next call returns that run (begun before the call), not a new one."""
    later = ("sleep", 0.0)
    ahead.run([("sleep", 0.5)], ahead=[later])
    asked = time.monotonic()
    (job, _, began), = ahead.run([later])
    assert job == later and began < asked
    assert ahead.used == 1 and ahead.unused == 0


def test_a_job_run_ahead_and_not_wanted_is_killed_not_waited_for(ahead):
    """A job run ahead that the next call neither asks for nor runs ahead is
    killed: the call takes its own job's time, not the unwanted one's 30 s."""
    ahead.run([("sleep", 0.2)], ahead=[("sleep", 30.0)])
    started = time.monotonic()
    (job, _, _), = ahead.run([("sleep", 0.0)])
    assert job == ("sleep", 0.0) and time.monotonic() - started < 5.0
    assert ahead.unused == 1 and not ahead._live


def test_a_job_s_exception_reaches_the_caller_and_nothing_is_left_running(ahead):
    with pytest.raises(ValueError, match="job 7 failed"):
        ahead.run([("fail", 7), ("sleep", 0.1)], ahead=[("sleep", 30.0)])
    assert not ahead._live


def test_nothing_runs_ahead_while_other_processes_keep_every_core_busy(ahead, monkeypatch):
    """Where the machine's cores are all taken (another case's processes), a
    run ahead would only slow the runs asked for: none is started, and the
    next call runs its job then."""
    monkeypatch.setattr("design.solvers.optimize.ahead.others_running", lambda: ahead.cores)
    later = ("sleep", 0.0)
    ahead.run([("sleep", 0.3)], ahead=[later])
    asked = time.monotonic()
    (_, _, began), = ahead.run([later])
    assert began >= asked and ahead.used == 0


def test_forked_map_returns_in_order_what_this_process_would():
    """A design's birds simulated in forked processes (forked_map): each
    item's value in the items' order, from processes other than this one; on
    one worker, here."""
    items = [("sleep", 0.05 * (3 - n)) for n in range(3)]
    there = forked_map(stamped, items, workers=2)
    here = forked_map(stamped, items, workers=1)
    assert [v[0] for v in there] == [v[0] for v in here] == items
    assert os.getpid() not in {v[1] for v in there}
    assert {v[1] for v in here} == {os.getpid()}


def test_a_second_job_asked_for_waits_for_a_free_core(ahead, monkeypatch):
    """Two simulations on one core take longer than one after the other:
    with every core taken but this call's first job's, its second begins
    only after the first has ended; with a core free, beside it."""
    monkeypatch.setattr("design.solvers.optimize.ahead.others_running", lambda: ahead.cores)
    (_, _, first), (_, _, second) = ahead.run([("sleep", 0.3), ("sleep", 0.0)])
    assert second - first >= 0.3
    monkeypatch.setattr("design.solvers.optimize.ahead.others_running", lambda: 0)
    (_, _, first), (_, _, second) = ahead.run([("sleep", 0.3), ("sleep", 0.0)])
    assert second - first < 0.25


def test_a_process_that_yields_the_cores_is_not_load(monkeypatch):
    """A background check at a lower priority (design/solvers/optimize/
    model_check.py) counts as load only while it runs: registered as
    yielding, a busy one is taken off the machine's running processes, a
    sleeping one is not running anyway."""
    from design.solvers.optimize import ahead as module
    busy = subprocess.Popen([sys.executable, "-c", "while True: pass"])
    asleep = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(30)"])
    try:
        time.sleep(0.5)
        assert module._runnable(busy.pid) and not module._runnable(asleep.pid)
        monkeypatch.setattr(module, "YIELDING", {busy.pid, asleep.pid})
        assert sum(module._runnable(p) for p in module.YIELDING) == 1
    finally:
        busy.kill()
        asleep.kill()
        busy.wait()
        asleep.wait()
    assert not module._runnable(busy.pid)
