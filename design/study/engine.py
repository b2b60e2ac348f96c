"""Running a study: every case, in this process one after another or on
Dask workers, each finished case stored as it finishes (design/study/store.py).

A task is ``task(case, upstream) -> dict``: ``upstream`` is the result of
the case named by ``case.after``, ``{key: result}`` when it names several
(None without one). The result holds
``"status"`` (a string) and may hold ``"hold_time_s"`` (a verified hold, s)
and ``"verified"`` (bool), which the progress line and summary show. The
engine adds ``"wall_time_s"`` (the task's wall time on its worker, s) and
``"worker"`` (``host:pid``), and round-trips the result through JSON on
the worker (numpy values become numbers, non-finite ones null), so the
serial and Dask runs return the same data and a downstream case gets what
the store holds.

Ctrl-C (design/interrupt.py) stops the study: no further case starts, the
running ones are cancelled and the cluster stopped, every finished case
stays in the store, and :class:`~design.errors.Interrupted` propagates.
"""

from __future__ import annotations

import json
import os
import socket
import sys
import time
import traceback
from collections.abc import Callable

from design import interrupt
from design.io.results import jsonable
from design.study.cases import FAILED, Case, StudyOptions, ordered
from design.study.cluster import dask_client, scheduler_address
from design.study.progress import StudyProgress
from design.study.store import open_store

#: the keys the engine adds to each result
ENGINE_KEYS = ("wall_time_s", "worker")
#: a failed task's traceback travels to the coordinating process under this
#: key, which prints it and removes it before the result is stored
_TRACEBACK = "_traceback"

#: task(case, result of the case it needs or None) -> result
Task = Callable[[Case, dict | None], dict]


def run_study(cases: list[Case], task: Task, *, options: StudyOptions, label: str,
              progress: StudyProgress | None = None, problem_digest: str = ""
              ) -> dict[str, dict]:
    """Run every case; return ``{key: result}`` in the order of ``cases``.

    ``task(case, result_of_case_after_or_None) -> dict`` must pickle (a
    module-level function, or a ``functools.partial`` of one binding, say,
    the parsed problem), as must the cases. A case whose ``after`` names
    another runs after it and receives its result. A task that raises is
    recorded as ``{"status": "error", "message": ...}`` (its traceback goes
    to stderr once) and the other cases still run; the cases after a failed
    one are recorded as ``"skipped"``, naming it. The caller must fail its
    run when any case has status ``"error"`` or ``"skipped"``: the engine
    only reports them.

    With ``options.store``, each finished case is written there as it
    finishes, and ``options.resume`` reuses the stored cases whose key,
    inputs and ``after`` are the current ones (not the failed ones);
    ``problem_digest`` identifies the problem the cases belong to: a store
    from another problem is refused.

    Raises
    ------
    ValueError
        A repeated key, an ``after`` that names no case, a cycle, inputs
        that are not JSON (naming the case).
    design.errors.StudyError
        The store holds cases and ``resume`` is false, or they are from
        another problem, or the file is no case store; the scheduler cannot
        be reached. Nothing has run and the store is as it was.
    design.errors.Interrupted
        Ctrl-C: every case finished before it is in the store.
    """
    order = ordered(cases)
    store = open_store(options.store, problem_digest, label, options.resume) \
        if options.store is not None else None
    results: dict[str, dict] = {}
    total = len(order)

    def finish(case: Case, result: dict) -> None:
        trace = result.pop(_TRACEBACK, "")
        if trace:
            if progress is not None:
                progress.traceback(case.key, trace)
            else:
                print(f"case {case.key!r} failed:\n{trace}", file=sys.stderr, end="")
        if store is not None:
            store.record(case, result)
        results[case.key] = result
        if progress is not None:
            progress.finished(case.key, result)

    def started(where: str) -> None:
        if progress is not None:
            progress.start(label, total, dict(results), where)

    try:
        if store is not None and options.resume:
            results.update(store.finished(order))
        todo = [case for case in order if case.key not in results]
        if not todo:
            started("nothing left to run")
        elif options.workers == 1 and scheduler_address(options) is None:
            started("this process, one case after another")
            _run_serial(todo, task, results, finish)
        else:
            _run_dask(todo, task, options, results, finish, started)
        if store is not None and not any(r["status"] in FAILED for r in results.values()):
            store.complete()
    finally:
        if store is not None:
            store.close()
        if progress is not None:
            progress.stop()
    if progress is not None:
        progress.summary(results)
    return {case.key: results[case.key] for case in cases}


def _run_serial(todo: list[Case], task: Task, done: dict[str, dict],
                finish: Callable[[Case, dict], None]) -> None:
    for case in todo:
        interrupt.checkpoint(f"before study case {case.key!r}")
        finish(case, _attempt(task, case, case.upstream(done)))


def _run_dask(todo: list[Case], task: Task, options: StudyOptions, done: dict[str, dict],
              finish: Callable[[Case, dict], None], started: Callable[[str], None]) -> None:
    """Submit every case, each needing its upstream's future (the scheduler
    orders them) or, resumed, its stored result; record them as they finish.
    Once submitted, the futures are held by ``as_completed`` alone, until
    each is collected: then Dask forgets a case's result (a case after it
    keeps it until it has run), so a worker lost later is not made to run
    collected cases again."""
    from distributed import as_completed

    with dask_client(options, len(todo)) as (client, where):
        started(where)
        submitted, cases = {}, {}
        for case in todo:
            # futures (inside a dict too) reach the task as their results
            upstream = {k: submitted.get(k, done.get(k)) for k in case.needs}
            future = client.submit(_attempt, task, case, case.upstream(upstream), pure=False)
            submitted[case.key], cases[future.key] = future, case
        running = as_completed(list(submitted.values()))
        del submitted, future
        try:
            for future in running:
                interrupt.checkpoint("while the study's cases ran")
                case = cases[future.key]
                result = _collected(future, case, done)
                # released here, not by the garbage collector: a Ctrl-C that
                # comes inside a __del__ is printed and lost there
                future.release()
                finish(case, result)
        except BaseException:
            client.cancel(list(running.futures))
            raise


def _collected(future, case: Case, done: dict[str, dict]) -> dict:
    """A finished future's result; one that Dask failed (its worker lost
    too often, or the case it needs failed so) as an error or skipped case."""
    if future.status == "finished":
        return future.result()
    failed = case.failed_upstream(done)
    if failed is not None:
        return _skipped(*failed)
    exc = future.exception()
    return {"status": "error", "message": f"{type(exc).__name__}: {exc}",
            "wall_time_s": None, "worker": None}


def _attempt(task: Task, case: Case, upstream: dict | None) -> dict:
    """Run one case where it is scheduled: its result, JSON round-tripped,
    with the wall time and worker; an exception becomes an error result,
    and a case whose needed case did not finish is skipped."""
    failed = case.failed_upstream({case.after: upstream} if isinstance(case.after, str)
                                  else upstream or {})
    if failed is not None:
        return _skipped(*failed)
    t0 = time.perf_counter()
    try:
        result = json.loads(json.dumps(jsonable(task(case, upstream)), allow_nan=False))
        if not isinstance(result, dict) or not isinstance(result.get("status"), str):
            raise TypeError(f"the task returned {type(result).__name__} without a "
                            f"'status' string, not a result dict")
    except Exception as exc:                  # noqa: BLE001  recorded; the study goes on
        result = {"status": "error", "message": f"{type(exc).__name__}: {exc}",
                  _TRACEBACK: traceback.format_exc()}
    result.update(wall_time_s=time.perf_counter() - t0,
                  worker=f"{socket.gethostname()}:{os.getpid()}")
    return result


def _skipped(need: str, upstream_status: str) -> dict:
    return {"status": "skipped", "message": f"not run: the case it needs, {need!r}, "
            f"ended {upstream_status}", "wall_time_s": 0.0, "worker": None}
