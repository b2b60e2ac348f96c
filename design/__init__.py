"""Optimal design and timing of compliant graspers: rubber elastica fingers
on two rotating drums that lift a bird off a moving conveyor belt.

Functions (each also a ``design`` command):

* :func:`simulate` -- run a scene (a beam, a finger against an object, a
  grasp); returns a :class:`BeamResult`, :class:`ContactResult` or
  :class:`GraspResult`.
* :func:`solve` -- optimise a design problem and verify the optimum;
  returns a :class:`DesignResult`.
* :func:`fit` -- calibrate a finger's EI(s) or a belt's speed profile from
  measurements; returns a :class:`FitResult`.
* :func:`check` -- validate any input file; returns a :class:`CheckResult`.
* :func:`animate` -- write a grasp or design run's 3-D animation from its
  output folder; returns the file's path.

A scene or problem is a YAML file's path, a shipped problem's name
(``design examples`` lists them) or the file's content as a dict. Every
result has a :class:`Status`, ``message``, ``success``, its summary (units in
the field names), ``files`` written and ``to_dict()`` (result.json, SI).
docs/guide.md describes every file and key; examples/quickstart.py runs one
of each.
"""

import os as _os

__version__ = "0.1.0"

# Thousands of tiny dense solves (a few to ~100 unknowns): BLAS threads only
# contend for the cores (benchmarks/contact_poses.py). A user's own setting
# wins; it has no effect if numpy was imported before this package.
_os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

_API = ("animate", "check", "fit", "simulate", "solve")
_RESULTS = ("BeamResult", "CheckResult", "ContactResult", "DesignResult", "FitResult",
            "GraspResult", "Result", "Status")
__all__ = [*_API, *_RESULTS, "__version__"]


def __getattr__(name: str):
    """The API, imported on first use: a process that needs only part of the
    toolkit (a study's worker, ``design --version``) does not load the
    solvers, reports and plotting."""
    if name in _API:
        from design import api
        return getattr(api, name)
    if name in _RESULTS:
        from design import result
        return getattr(result, name)
    raise AttributeError(f"module 'design' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(__all__)
