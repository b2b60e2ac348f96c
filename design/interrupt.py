"""Ctrl-C (SIGINT) during a run: stop within about a second, say where, and
never finish with an answer that the interrupt changed.

The handler raises :class:`~design.errors.Interrupted`. CasADi catches an
exception raised while it runs: Ipopt returns ``NonIpopt_Exception_Thrown``
and a Function call raises a ``RuntimeError``, which the design loop or a
contact solver would take for a failed solve (seen: an interrupted outer
iteration rejected, and a different design verified). So a Ctrl-C inside a
CasADi call also sets a profile hook that raises ``Interrupted`` as the
call returns to the toolkit's code, in place of what CasADi made of it.
Where the hook cannot be set (a profiler runs), the handler only records
the request: Ipopt's iteration callback stops the solve (:func:`requested`)
and :func:`checkpoint` raises after it and before the first result file.

Writing a result file starts the run's output phase (:func:`writing`): a
Ctrl-C from then on lets every file be written and stops the run after
them, so a run leaves either no file of its own or all of them.

A second Ctrl-C kills the process at once (the default action).
"""

from __future__ import annotations

import importlib.util
import os
import signal
import sys
import threading
from contextlib import contextmanager
from functools import cache
from pathlib import Path

from design.errors import Interrupted

_DESIGN = str(Path(__file__).resolve().parent) + os.sep


class _State:
    #: the handler is installed (by the outermost :func:`handled`)
    installed: bool = False
    #: where Python saw the Ctrl-C (None: not pressed)
    seen: str | None = None
    #: the run has started writing its result files
    writing: bool = False


def requested() -> bool:
    """Has Ctrl-C been pressed during the current run (under :func:`handled`)?"""
    return _State.installed and _State.seen is not None


def checkpoint(where: str) -> None:
    """Raise :class:`Interrupted` (stopped ``where``) if Ctrl-C was pressed,
    unless the run is writing its results."""
    if requested() and not _State.writing:
        raise Interrupted(f"{where} (Ctrl-C seen {_State.seen})")


def writing() -> None:
    """Called before each result file is written: a Ctrl-C that came before
    the first stops the run here; one that comes later waits for the run's
    last file."""
    checkpoint("before writing any result")
    _State.writing = _State.installed


@contextmanager
def handled():
    """Run a command with the Ctrl-C handler installed, restoring the previous
    one after. Main thread only (Python delivers signals nowhere else);
    nested calls use the outer one's."""
    if _State.installed or threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGINT, _on_sigint)
    _State.installed, _State.seen, _State.writing = True, None, False
    try:
        yield
    finally:
        _State.installed = False
        signal.signal(signal.SIGINT, previous)
        if sys.getprofile() is _raise_on_return:
            sys.setprofile(None)
    if _State.seen is not None:
        when = "after writing the results" if _State.writing else "as the command ended"
        raise Interrupted(f"{when} (Ctrl-C seen {_State.seen})", written=_State.writing)


def stopped(exc: BaseException) -> str | None:
    """The line a command prints when Ctrl-C stopped the run that ``exc``
    ended (a library may have turned the interrupt into its own error);
    None if the run was not interrupted."""
    if isinstance(exc, Interrupted):
        where, written = exc.where, exc.written
    elif _State.seen is not None:
        where, written = f"{_State.seen} ({type(exc).__name__} on the way out)", False
    else:
        return None
    return (f"interrupted (Ctrl-C): stopped {where}; "
            + ("every result file had been written" if written else "nothing was written"))


def _on_sigint(signum, frame) -> None:
    signal.signal(signal.SIGINT, signal.SIG_DFL)      # a second Ctrl-C kills
    _State.seen = _location(frame)
    if _State.writing:
        return
    if _inside_casadi(frame):
        if sys.getprofile() is not None:               # a profiler's: checkpoints only
            return
        sys.setprofile(_raise_on_return)
    raise Interrupted(_State.seen)


def _raise_on_return(frame, event, arg) -> None:
    """Profile hook: raise as a CasADi call returns to the toolkit's code,
    with a result or with the error that CasADi made of the interrupt."""
    if event == "return" and frame.f_code.co_filename.startswith(_casadi()) and \
            not _inside_casadi(frame.f_back) and not _State.writing:
        sys.setprofile(None)
        raise Interrupted(f"as a CasADi call returned {_location(frame.f_back)}")


def _inside_casadi(frame) -> bool:
    while frame is not None:
        if frame.f_code.co_filename.startswith(_casadi()):
            return True
        frame = frame.f_back
    return False


@cache
def _casadi() -> str:
    """CasADi's package folder (found without importing it)."""
    return os.path.join(importlib.util.find_spec("casadi").submodule_search_locations[0], "")


def _location(frame) -> str:
    """'in function (design/path.py:line)' of the innermost toolkit frame."""
    inner = frame
    while frame is not None and not frame.f_code.co_filename.startswith(_DESIGN):
        frame = frame.f_back
    frame = frame or inner
    if frame is None:
        return "outside Python code"
    path = frame.f_code.co_filename
    if path.startswith(_DESIGN):
        path = os.path.join("design", path[len(_DESIGN):])
    return f"in {frame.f_code.co_name} ({path}:{frame.f_lineno})"
