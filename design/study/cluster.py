"""The Dask client a study's cases run on: a LocalCluster started and
stopped for the study, or a running scheduler's (``tcp://HOST:PORT``).

The LocalCluster has one worker process per core (or ``workers``, and no
more than there are cases to run), one thread each, no dashboard, and its
workers run with one BLAS/OpenMP thread. They are not daemons: a case's
pattern search may simulate in two forked processes of its own
(design/solvers/optimize/pattern_search.py), which keeps both cores busy
when one long case outlasts the others. Its nannies restart a worker
process that dies, and the scheduler gives the lost case to another worker:
a case may be lost with its worker :data:`ALLOWED_FAILURES` times before it
is recorded as an error (a running scheduler applies its own setting,
Dask's default also 3). Dask's log lines below errors are silenced while
the study runs.

A LocalCluster takes about a second to start and stop, and a worker loads
the solvers with its first case of a design problem: a study gains from
workers when its cases take seconds (``python -m benchmarks.study``
measures the overhead; docs/performance.md).

Worker processes compiling the same CasADi function at the same time is
safe: each builds in its own temporary folder and moves the library into
the cache with ``os.replace`` (design/solvers/compiled.py), so a process
finds no library or a whole one, and one already loaded keeps its copy.
"""

from __future__ import annotations

import logging
import os
import signal
from collections.abc import Iterator
from contextlib import contextmanager

from design import __version__
from design.errors import StudyError
from design.study.cases import StudyOptions

#: times a case may be lost with its worker (killed, out of memory) and run again
ALLOWED_FAILURES = 3
#: each worker process computes with one thread (the cases are the parallelism)
WORKER_ENV = {"OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1"}
#: seconds to wait for a running scheduler to answer
CONNECT_TIMEOUT = 10


def scheduler_address(options: StudyOptions) -> str | None:
    """The running scheduler the study uses: ``options.scheduler``, else,
    when ``workers`` was not given either, ``$DASK_SCHEDULER_ADDRESS``."""
    if options.scheduler:
        return options.scheduler
    if options.workers is None:
        return os.environ.get("DASK_SCHEDULER_ADDRESS") or None
    return None


@contextmanager
def dask_client(options: StudyOptions, cases: int) -> Iterator[tuple[object, str]]:
    """A ``distributed.Client`` for ``cases`` cases and where they run (for
    the progress line); the LocalCluster, if one was started, is stopped
    after. :class:`StudyError` if the scheduler cannot be reached, or a
    worker runs another version of the toolkit."""
    import dask
    from distributed import Client

    address = scheduler_address(options)
    # the local workers are not daemons, so that a case's pattern search may
    # fork its two processes (a population's search outlasts the study's
    # other cases); the nannies read it as they start a worker, also later
    with _quiet_dask_logs(), dask.config.set({"distributed.worker.daemon": False}):
        if address:
            try:
                client = Client(address, timeout=CONNECT_TIMEOUT)
            except (OSError, TimeoutError) as exc:
                raise StudyError(f"cannot reach the Dask scheduler at {address}: {exc}") \
                    from None
            cluster = None
        else:
            n = min(options.workers or os.cpu_count() or 1, cases)
            cluster = _local_cluster(n)
            client = Client(cluster)
        try:
            if address:
                _check_versions(client, address)
                n = len(client.scheduler_info()["workers"])
                where = f"the Dask scheduler at {address} ({n} workers now)"
            else:
                where = f"{n} local worker process{'es' if n != 1 else ''}"
            yield client, where
        finally:
            client.close()
            if cluster is not None:
                cluster.close()


def _local_cluster(n: int):
    from distributed import LocalCluster

    return LocalCluster(n_workers=n, threads_per_worker=1, processes=True,
                        dashboard_address=None, silence_logs=logging.ERROR,
                        env=WORKER_ENV, preload=[__name__],
                        # the scheduler's HTTP server (health, metrics) starts
                        # even without a dashboard, on 8787 unless told
                        # otherwise: a second study warned of the port
                        scheduler_kwargs={"allowed_failures": ALLOWED_FAILURES,
                                          "dashboard": False, "dashboard_address": ":0"})


def dask_setup(worker) -> None:
    """Each LocalCluster worker process, as it starts (this module is its
    preload): a Ctrl-C at the terminal reaches every process of the
    command, and the coordinating process stops the workers itself, so the
    workers ignore it (else each prints a traceback as it dies)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def _toolkit_version() -> str:
    return __version__


def _check_versions(client, address: str) -> None:
    """Every worker of a running scheduler must run this toolkit version."""
    other = {worker: version for worker, version in client.run(_toolkit_version).items()
             if version != __version__}
    if other:
        raise StudyError(f"workers of {address} run other versions of the toolkit than "
                         f"this one ({__version__}): "
                         + ", ".join(f"{w}: {v}" for w, v in sorted(other.items())))


@contextmanager
def _quiet_dask_logs() -> Iterator[None]:
    """Dask's loggers in this process at ERROR (a restarted worker, a closed
    connection are routine here), as they were after. Each one: Dask gives
    some (``distributed.client``) a level of their own."""
    names = {"distributed", "dask", *(name for name in logging.root.manager.loggerDict
                                      if name.split(".")[0] in ("distributed", "dask"))}
    loggers = [logging.getLogger(name) for name in sorted(names)]
    levels = [log.level for log in loggers]
    for log in loggers:
        log.setLevel(logging.ERROR)
    tornado = logging.getLogger("tornado.application")
    tornado.addFilter(_cancel_after_interrupt)
    try:
        yield
    finally:
        for log, level in zip(loggers, levels):
            log.setLevel(level)
        tornado.removeFilter(_cancel_after_interrupt)


def _cancel_after_interrupt(record: logging.LogRecord) -> bool:
    """Drop the event loop's report of distributed's ``sync`` cancelling the
    call that Ctrl-C interrupted in this thread (the cancel callback raises
    when the call has ended meanwhile): about 1 interrupted study in 10
    printed it as an ERROR with a traceback (tests/test_study_dask.py)."""
    return "sync.<locals>.cancel" not in record.getMessage()
