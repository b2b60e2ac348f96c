"""Independent simulations in forked processes.

A design's birds, or the two designs of a pattern search's poll, are
simulated independently of each other: on a machine with two cores they run
in two forked processes, each computing exactly what this process would, in
about half the wall time. Forking needs ``fork`` and a process that may have
children (not a daemon: a process pool's worker simulates in turn, here);
elsewhere everything runs in this process.
"""

from __future__ import annotations

import multiprocessing
import os
from collections.abc import Callable, Sequence

from design.solvers.optimize.ahead import Ahead


def processes(workers: int | None, tasks: int | None = None) -> int:
    """How many processes to use: ``workers`` (None: one per core, at most
    two), no more than ``tasks``, and one where this process cannot fork."""
    wanted = min(2, os.cpu_count() or 1) if workers is None else workers
    if tasks is not None:
        wanted = min(wanted, tasks)
    usable = "fork" in multiprocessing.get_all_start_methods() and \
        not multiprocessing.current_process().daemon
    return wanted if wanted > 1 and usable else 1


def forked_map(fn: Callable, items: Sequence, workers: int | None = None) -> list:
    """``[fn(item) for item in items]``, the items handed out in order, each to
    a forked process of its own, :func:`processes` at a time (``fn`` need not
    pickle, its results must)."""
    count = processes(workers, len(items))
    if count == 1:
        return [fn(item) for item in items]
    runner = Ahead(fn, id, count)
    try:
        return runner.run(items)
    finally:
        runner.close()
