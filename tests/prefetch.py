"""Expensive, deterministic computations that the selected tests will ask
for, computed ahead in one worker process, on the machine's other core,
while the tests before them run.

The default run spends about half of its time in simulations, references,
NLP and design solves that are known before the first test starts
(tests/conftest.py lists them). The worker takes them in the order
the tests will need them and sends each result back whole (pickled: the
same numbers, as the code and its inputs are the same; checked on the short
grasp's runs, every record hashed). A test that asks for one the worker has
not started takes it over and computes it itself, so neither process waits
for work the other has not begun; one the worker is computing it waits for;
one the worker failed, or all of them if the worker is gone, it computes
itself. The answer is the same either way, only the time changes.

On a machine whose other core is busy the worker only shares it, and the
tests take over what it has not reached. Set ``DESIGN_TEST_PREFETCH=0`` to
compute everything in the test process."""

from __future__ import annotations

import multiprocessing
import os
import queue
from pathlib import Path
from typing import Callable

#: a job's state, shared with the worker
WAITING, TAKEN_BY_WORKER, TAKEN_HERE = 0, 1, 2

#: key -> result, as received from the worker
_results: dict[str, object] = {}
#: keys the worker may still send
_pending: set[str] = set()
#: key -> (index, the arguments it was given)
_jobs: dict[str, tuple[int, tuple]] = {}
_worker: dict = {}


def enabled() -> bool:
    return os.environ.get("DESIGN_TEST_PREFETCH", "1") != "0"


def start(jobs: list[tuple[str, Callable, tuple, tuple[str, ...]]]) -> None:
    """Start the worker on ``jobs``, (key, function, args, needs) in the
    order the tests will need them; functions and arguments must pickle
    (module-level functions). A job that ``needs`` others' results (in the
    worker's own caches) is left to the tests unless the worker computed
    those itself."""
    if not jobs or _worker or not enabled():
        return
    context = multiprocessing.get_context("spawn")     # no fork of a process holding CasADi
    # a queue, not a pipe: its feeder thread sends while the worker goes on with
    # the next job (a pipe's send blocks until the tests read the result)
    results = context.Queue()
    states = context.Array("b", len(jobs))              # WAITING, with its own lock
    process = context.Process(target=_work, args=(results, states, jobs), name="test-prefetch",
                              daemon=True)
    process.start()
    _worker.update(process=process, results=results, states=states)
    _pending.update(job[0] for job in jobs)
    _jobs.update((key, (k, args)) for k, (key, _, args, _) in enumerate(jobs))


def stop() -> None:
    """End the worker (at the end of the session: whatever it has not sent
    is not needed)."""
    process = _worker.pop("process", None)
    results = _worker.pop("results", None)
    if process is not None and process.is_alive():
        process.terminate()
        process.join(5)
    if results is not None:
        results.cancel_join_thread()
        results.close()
    _pending.clear()


def folder(key: str, fresh: Callable[[], Path]) -> Path:
    """The folder the worker was given for ``key`` (a job whose first
    argument is a folder made when it is scheduled), or ``fresh()`` where it
    was not given the job."""
    return _jobs[key][1][0] if key in _jobs else fresh()


def result(key: str, function: Callable, *args):
    """``function(*args)``: the worker's result if it has computed or is
    computing ``key``, else computed here."""
    if key in _results:
        return _results.pop(key)
    if key in _pending and _take(key):
        return function(*args)
    while key in _pending:
        try:
            got, value, failed = _worker["results"].get(timeout=1.0)
        except queue.Empty:
            if not _worker["process"].is_alive() and _worker["results"].empty():
                _pending.clear()                       # the worker is gone
            continue
        except (EOFError, OSError, ValueError):        # the queue broke
            _pending.clear()
            break
        _pending.discard(got)
        if not failed:
            _results[got] = value
    return _results.pop(key) if key in _results else function(*args)


def _take(key: str) -> bool:
    """Take ``key`` over from the worker unless it has started it."""
    states = _worker["states"]
    with states.get_lock():
        k = _jobs[key][0]
        if states[k] == WAITING:
            states[k] = TAKEN_HERE
            _pending.discard(key)
            return True
    return False


def _work(results, states, jobs) -> None:
    # whatever a job prints is not the tests' output (the worker inherited the
    # test process's standard streams, which pytest may be capturing)
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, 1)
    os.dup2(devnull, 2)
    done = set()
    for k, (key, function, args, needs) in enumerate(jobs):
        if not done.issuperset(needs):                 # it would compute them again
            continue
        with states.get_lock():
            if states[k] != WAITING:                   # the tests took it over
                continue
            states[k] = TAKEN_BY_WORKER
        try:
            value, failed = function(*args), False
            done.add(key)
        except Exception as exc:                       # noqa: BLE001  the test computes it
            value, failed = repr(exc), True
        results.put((key, value, failed))
    results.close()
    results.join_thread()                              # everything sent before the exit
