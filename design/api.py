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
from design.study.cases import StudyOptions
from design.study.store import STORE, check_store

RUNNERS = {BeamScene: beam_run.run, ContactScene: contact_run.run, GraspScene: grasp_run.run,
           DesignProblem: solve_run.run}


def run(scene: object, source: str | Path | Mapping, progress: Progress | None = None,
        study: StudyOptions | None = None) -> RunOutput:
    """Run a validated scene read from ``source``; a file's name, as given,
    is kept in the result as ``scene_file`` (the report's command to rerun it).
    A design problem's runner is given ``study``: how its cases run (None:
    the defaults, no case store)."""
    runner = RUNNERS[type(scene)]
    output = runner(scene, progress, study=study) if isinstance(scene, DesignProblem) \
        else runner(scene, progress)
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
        return _run_and_write(load_scene(source), source, out, progress)


def solve(source: str | Path | Mapping, out: str | Path | None = None,
          progress: Progress | None = None, *, workers: int | None = None,
          scheduler: str | None = None, resume: bool = False) -> dict:
    """Solve a design problem (``kind: design``, a path or the file's content):
    optimise, verify, and return the dict ``design solve`` writes to
    ``result.json`` (with ``out``, also write it, the CSV tables,
    ``optimum.yaml`` and ``report.html`` there). ``result["status"]`` says how
    it ended: ``verified``, ``no improvement found`` (the baseline is the
    answer), ``failed verification`` or ``error`` (design/run/solve.py).

    The problem's cases run on ``workers`` local processes (None: one per
    core; 1: in this process, one after another) or on the Dask
    ``scheduler`` at ``tcp://HOST:PORT``; with ``out``, each finished case
    is kept in ``out/cases.sqlite`` and ``resume`` reuses them (see
    :mod:`design.study`). Raises :class:`~design.errors.StudyError`, before
    the run, if that store holds cases and ``resume`` is false."""
    scene = load_scene(source)
    if not isinstance(scene, DesignProblem):
        raise ValueError("design.solve needs a design problem (kind: design); "
                         "use design.simulate for scenes")
    study = StudyOptions(workers=workers, scheduler=scheduler, resume=resume,
                         store=Path(out) / STORE if out is not None else None)
    if out is not None:
        check_output_folder(Path(out))
        check_store(study.store, resume)
    with interrupt.handled():
        return _run_and_write(scene, source, out, progress, study)


def _run_and_write(scene: object, source: str | Path | Mapping, out: str | Path | None,
                   progress: Progress | None, study: StudyOptions | None = None) -> dict:
    """Run ``scene`` and, with ``out``, write its files there; its result."""
    output = run(scene, source, progress, study)
    if out is not None:
        write_run(Path(out), output)
    return output.result


def animate(result_dir: str | Path, out: str | Path | None = None, speed: float = 0.25,
            progress: Progress | None = None) -> Path:
    """Write the 3-D animation of the grasp or design run whose output folder
    is ``result_dir`` from its result.json (``design animate``): ``out``
    ending .mp4 (needs ffmpeg), .gif or .html; None: RESULT_DIR/animation.mp4,
    or .gif without ffmpeg. Videos play at ``speed`` times real time. The
    fingers are solved again at the frame states the result keeps. Returns
    the file written; raises :class:`design.report.animate.AnimateError`
    (nothing written) for a result or output that will not do."""
    from design.report.animate import animate as write_animation

    return write_animation(result_dir, out, speed, progress)


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
