"""Cheap tasks for the study tests, module-level so that Dask workers
import them: a few milliseconds each, a deterministic result from the
case's inputs and its upstream's result, and every call recorded as a
file in a folder (so a test counts the calls, in any process)."""

from __future__ import annotations

import os
import signal
import time
import uuid
from pathlib import Path
from urllib.parse import quote, unquote

from design.errors import Interrupted
from design.study import Case


def value(calls: Path, case: Case, upstream: dict | None, *, kill: str | None = None,
          spare: int | None = None) -> dict:
    """``hold_time_s`` = x / 100 plus the upstream's (the sum of several
    upstreams'); ``chain`` lists the keys up the chain (each upstream's in
    turn). Raises for inputs ``fail``. The case keyed ``kill``
    kills its own process on its first attempt, 0.2 s after it is called
    (the cases finished before it are collected by then), unless the
    process is ``spare`` (the test's own)."""
    time.sleep(case.inputs.get("sleep", 0.005))
    (calls / f"{quote(case.key, safe='')} {os.getpid()} {uuid.uuid4().hex}").touch()
    if case.key == kill and os.getpid() != spare and not (calls / "killed").exists():
        (calls / "killed").touch()
        time.sleep(0.2)
        os.kill(os.getpid(), signal.SIGKILL)
    if case.inputs.get("fail"):
        raise ValueError(f"case {case.key} fails on purpose")
    ups = [] if upstream is None else [upstream] if "status" in upstream else \
        list(upstream.values())
    up = {"hold_time_s": sum(u["hold_time_s"] for u in ups),
          "chain": [key for u in ups for key in u["chain"]]}
    return {"status": "verified", "verified": True,
            "hold_time_s": case.inputs["x"] / 100 + up["hold_time_s"],
            "max_finger_force_N": 10.0 * case.inputs["x"], "chain": up["chain"] + [case.key]}


def interrupted(calls: Path, case: Case, upstream: dict | None, *, at: str) -> dict:
    """:func:`value`, but Ctrl-C is pressed during the case keyed ``at``."""
    if case.key == at:
        raise Interrupted(f"in case {at} (simulated)")
    return value(calls, case, upstream)


def called(calls: Path) -> list[str]:
    """The keys of the calls made, sorted."""
    return sorted(unquote(p.name.split()[0]) for p in calls.iterdir() if p.name != "killed")


def forked(case: Case, upstream: dict | None) -> dict:
    """Squares ``x`` in a pool of two forked processes, as a pattern
    search's simulations are (design/solvers/optimize/pattern_search.py)."""
    import multiprocessing

    with multiprocessing.get_context("fork").Pool(2) as pool:
        squares = pool.map(_square, [case.inputs["x"]] * 2)
    return {"status": "done", "hold_time_s": float(sum(squares)),
            "daemon": multiprocessing.current_process().daemon}


def _square(x: float) -> float:
    return x * x
