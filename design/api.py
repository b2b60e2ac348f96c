"""The Python API behind the ``design`` command.

>>> import design
>>> result = design.simulate({"kind": "beam", "finger": {"length": 0.2, "EI": 0.08},
...                           "load": {"F": 15, "alpha": "90 deg", "at": "4 in"},
...                           "solver": {"method": "frisch-fay"}})
>>> round(result["cases"][0]["tip"]["y"], 5)
0.04918
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

from design import interrupt
from design.io.beam_scene import BeamScene
from design.io.contact_scene import ContactScene
from design.io.design_problem import DesignProblem
from design.io.grasp_scene import GraspScene
from design.io.results import check_output_folder
from design.io.scene import check_file, load_fit, load_scene
from design.report import write_run
from design.run import Progress, RunOutput
from design.run import beam as beam_run
from design.run import contact as contact_run
from design.run import grasp as grasp_run
from design.run import solve as solve_run

RUNNERS = {BeamScene: beam_run.run, ContactScene: contact_run.run, GraspScene: grasp_run.run,
           DesignProblem: solve_run.run}


def run(scene: object, source: str | Path | Mapping, progress: Progress | None = None
        ) -> RunOutput:
    """Run a validated scene read from ``source``; a file's name, as given,
    is kept in the result as ``scene_file`` (the report's command to rerun it)."""
    output = RUNNERS[type(scene)](scene, progress)
    if not isinstance(source, Mapping):
        output.result["scene_file"] = str(source)
    return output


def run_scene(source: str | Path | Mapping, progress: Progress | None = None) -> RunOutput:
    """Validate and run a scene; the full output (result and CSV tables).
    Ctrl-C raises :class:`design.errors.Interrupted` (see :mod:`design.interrupt`)."""
    scene = load_scene(source)
    with interrupt.handled():
        return run(scene, source, progress)


def simulate(source: str | Path | Mapping, out: str | Path | None = None,
             progress: Progress | None = None) -> dict:
    """Solve a scene given as a file path or as the file's content (a mapping).

    Returns the dict that ``design simulate`` writes to ``result.json``; with
    ``out``, also writes it, the CSV tables and report.html there.

    Raises
    ------
    design.errors.ProblemFileError
        If the scene has problems (nothing is written then).
    design.io.results.OutputFolderError
        If ``out`` cannot be written to (checked before the run).
    design.errors.Interrupted
        On Ctrl-C (a ``KeyboardInterrupt``): nothing was written, or, if it
        came while the files were being written, all of them were.
    """
    if out is not None:
        check_output_folder(Path(out))
    with interrupt.handled():
        output = run_scene(source, progress)
        if out is not None:
            write_run(Path(out), output)
    return output.result


def solve(source: str | Path | Mapping, out: str | Path | None = None,
          progress: Progress | None = None) -> dict:
    """Solve a design problem (``kind: design``, a path or the file's content):
    optimise, verify, and return the dict ``design solve`` writes to
    ``result.json`` (with ``out``, also write it, the CSV tables,
    ``optimum.yaml`` and ``report.html`` there). ``result["status"]`` says how
    it ended: ``verified``, ``no improvement found`` (the baseline is the
    answer), ``failed verification`` or ``error`` (design/run/solve.py)."""
    scene = load_scene(source)
    if not isinstance(scene, DesignProblem):
        raise ValueError("design.solve needs a design problem (kind: design); "
                         "use design.simulate for scenes")
    return simulate(source, out, progress)


def check(source: str | Path | Mapping) -> object:
    """Validate any input file (scene or model); returns the object it describes."""
    return check_file(source)


def fit(source: str | Path | Mapping, out: str | Path | None = None,
        progress: Progress | None = None) -> dict:
    """Run a fit problem (``kind: fit``, a path or the file's content):
    calibrate a finger's EI(s) or a belt's speed profile from measurements
    and return the dict ``design fit`` writes to ``result.json`` (with
    ``out``, also write it, the model file, the CSV tables and
    ``report.html`` there). Raises :class:`~design.errors.ProblemFileError`
    for bad input (nothing written)."""
    from design.report.fit import write_fit
    from design.run.fit import run as fit_run

    problem = load_fit(source)
    if out is not None:
        check_output_folder(Path(out))
    with interrupt.handled():
        output = fit_run(problem, progress)
        if not isinstance(source, Mapping):
            output.result["scene_file"] = str(source)
        if out is not None:
            write_fit(Path(out), output)
    return output.result
