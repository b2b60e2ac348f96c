"""Simulations in forked processes, one process each, some run ahead.

A pattern search evaluates its points a poll at a time: two simulations,
a decision, the next two. Where one of them ends early (a candidate ruled
out) its core would wait for the other. Here each simulation is a forked
process of its own, at most one per core at a time, and while the ones
asked for run, a free core starts one the caller will probably ask for
next (the next polls', if this one moves nothing). A simulation run ahead
is the computation it would be when asked for (the same job: design, bird
and rival), so what the caller gets, and decides, does not depend on
whether it ran ahead; one no longer wanted is killed.

A job runs ahead only on a core that is free: where other processes keep
every core busy (two cases of a study, each with its processes), a run
ahead would take time from the runs asked for. So does a second job asked
for: it waits for a free core, as two simulations sharing one take longer
than one after the other.

A forked process computes exactly what this one would: it starts from this
process's state at the fork, with its built functions.
"""

from __future__ import annotations

import multiprocessing
import os
from collections.abc import Callable, Hashable, Sequence
from multiprocessing.connection import wait
from pathlib import Path


class _Forked:
    """One call ``fn(job)`` in a forked process."""

    def __init__(self, context, fn: Callable, job):
        self._receive, send = context.Pipe(duplex=False)
        self._process = context.Process(target=_call, args=(fn, job, send), daemon=True)
        self._process.start()
        send.close()
        self._outcome = None

    @property
    def connection(self):
        return self._receive

    def done(self) -> bool:
        """Whether the call has answered; its process then has ended, so that
        it no longer counts among the machine's running processes."""
        if self._outcome is None and self._receive.poll():
            self._collect()
        return self._outcome is not None

    def _collect(self) -> None:
        try:
            self._outcome = self._receive.recv()
        except EOFError:
            self._outcome = ("error", RuntimeError(
                f"a simulation's process ended without an answer "
                f"(exit code {self._process.exitcode})"))
        self._process.join()
        self._receive.close()

    def value(self):
        """The call's value (waiting for it), or its exception raised here."""
        if self._outcome is None:
            self._collect()
        kind, value = self._outcome
        if kind == "error":
            raise value
        return value

    def kill(self) -> None:
        if self._outcome is None:
            self._process.kill()
            self._process.join()
            self._receive.close()
            self._outcome = ("error", RuntimeError("killed: no longer wanted"))


def _call(fn: Callable, job, send) -> None:
    try:
        outcome = ("value", fn(job))
    except BaseException as exc:  # noqa: BLE001  (handed to the caller, raised there)
        outcome = ("error", exc)
    try:
        send.send(outcome)
    except Exception as exc:  # noqa: BLE001  (an exception that does not pickle)
        send.send(("error", RuntimeError(f"{type(outcome[1]).__name__}: {outcome[1]} "
                                         f"(not passed on: {exc})")))
    send.close()


#: how often (s) jobs waiting for a free core look for one
LOOK_AGAIN = 0.05


#: processes of this run that yield the cores (background checks at a
#: lower priority, design/solvers/optimize/model_check.py): not load
YIELDING: set[int] = set()


def others_running() -> int:
    """Processes running or ready to run on this machine now, besides this
    one and those that yield (:data:`YIELDING`): Linux's /proc/loadavg;
    elsewhere the load average of the last minute, rounded."""
    try:
        running = int(Path("/proc/loadavg").read_text().split()[3].split("/")[0]) - 1
    except (OSError, ValueError, IndexError):
        return round(os.getloadavg()[0])
    return running - sum(_runnable(pid) for pid in YIELDING)


def _runnable(pid: int) -> bool:
    """Whether process ``pid`` is running or ready to run (Linux's /proc)."""
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] == "R"
    except (OSError, IndexError):
        return False


class Ahead:
    """Calls of ``fn`` on ``processes`` cores, each in a forked process;
    ``key(job)`` names what a job computes (equal keys, equal values)."""

    def __init__(self, fn: Callable, key: Callable[[object], Hashable], processes: int):
        self.fn, self.key, self.processes = fn, key, processes
        self.cores = os.cpu_count() or 1
        self._context = multiprocessing.get_context("fork")
        #: jobs run ahead, by key, running or done, not yet asked for
        self._ahead: dict[Hashable, _Forked] = {}
        #: jobs run ahead and then asked for, and those never asked for
        self.used = self.unused = 0
        self._live: set[_Forked] = set()

    def run(self, jobs: Sequence, ahead: Sequence = ()) -> list:
        """``[fn(job) for job in jobs]``; while they run, a free core (of
        this call's and of the machine's) starts the jobs of ``ahead`` in
        turn (a later call's, probably). Jobs run ahead that are neither in
        ``jobs`` nor in ``ahead`` are killed."""
        try:
            return self._run(jobs, ahead)
        except BaseException:
            self.close()
            raise

    def _run(self, jobs: Sequence, ahead: Sequence) -> list:
        keys = [self.key(job) for job in jobs]
        wanted = set(keys) | {self.key(job) for job in ahead}
        for k in [k for k in self._ahead if k not in wanted]:
            unwanted = self._ahead.pop(k)
            unwanted.kill()
            self._live.discard(unwanted)
            self.unused += 1
        forked: list[_Forked | None] = [self._ahead.pop(k, None) for k in keys]
        self.used += sum(f is not None for f in forked)
        todo = [i for i, f in enumerate(forked) if f is None]
        later = [job for job in ahead if self.key(job) not in self._ahead
                 and self.key(job) not in keys]
        while True:
            running = [f for f in [*forked, *self._ahead.values()]
                       if f is not None and not f.done()]
            # a job asked for beyond the first runs beside it on a free core
            # only: two processes on one core take longer than one after the other
            while todo and (not running or len(running) < self.processes
                            and others_running() < self.cores):
                i = todo.pop(0)
                forked[i] = self._fork(jobs[i])
                running.append(forked[i])
            while len(running) < self.processes and later and others_running() < self.cores:
                job = later.pop(0)
                self._ahead[self.key(job)] = self._fork(job)
                running.append(self._ahead[self.key(job)])
            if not todo and all(f.done() for f in forked):
                values = [f.value() for f in forked]
                self._live -= set(forked)
                return values
            waiting = [f.connection for f in running if not f.done()]
            if waiting:
                # jobs waiting for a core look again now and then for a free one
                wait(waiting, timeout=LOOK_AGAIN if todo else None)

    def _fork(self, job) -> _Forked:
        forked = _Forked(self._context, self.fn, job)
        self._live.add(forked)
        return forked

    def close(self) -> None:
        """Kill every process still running (a failed or interrupted call's,
        and those run ahead)."""
        for forked in self._live:
            forked.kill()
        self._live.clear()
        self._ahead.clear()
