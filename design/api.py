"""The Python API behind the ``design`` command: :func:`simulate`,
:func:`solve`, :func:`fit`, :func:`check` and :func:`animate`.

Each run returns a typed result (design/result.py): its status, message,
summary, the files written and ``to_dict()``, which is what result.json holds.

>>> import design
>>> result = design.simulate({"kind": "beam", "finger": {"length": 0.2, "EI": 0.08},
...                           "load": {"F": 15, "alpha": "90 deg", "at": "4 in"},
...                           "solver": {"method": "frisch-fay"}})
>>> result.status, result.success
(<Status.FINISHED: 'finished'>, True)
>>> round(result.to_dict()["cases"][0]["tip"]["y"], 5)
0.04918
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import replace
from pathlib import Path

from design import interrupt
from design.errors import ProblemFileError
from design.io.beam_scene import BeamScene
from design.io.contact_scene import ContactScene
from design.io.design_problem import DesignProblem
from design.io.grasp_scene import GraspScene
from design.io.results import check_output_folder
from design.io.scene import check_file, load_fit, load_scene
from design.report import write_run
from design.result import (BeamResult, CheckResult, ContactResult, DesignResult, FitResult,
                           GraspResult, Result, Status, result_of)
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
    is kept in the record as ``scene_file`` (the report's command to rerun
    it). A design problem's runner is given ``study``: how its cases run
    (None: the defaults, no case store)."""
    runner = RUNNERS[type(scene)]
    output = runner(scene, progress, study=study) if isinstance(scene, DesignProblem) \
        else runner(scene, progress)
    if not isinstance(source, Mapping):
        output.result["scene_file"] = str(source)
    return output


def finish(output: RunOutput, out: str | Path | None = None,
           write: Callable[[Path, RunOutput], list[Path]] = write_run) -> Result:
    """A run's typed result; with ``out``, its files written there first
    (result.json from :meth:`~design.result.Result.to_dict`, the tables,
    the report)."""
    result = result_of(output.result, output.ok)
    if out is None:
        return result
    written = write(Path(out), replace(output, result=result.to_dict()))
    return replace(result, files=tuple(written))


def simulate(source: str | Path | Mapping, out: str | Path | None = None,
             progress: Progress | None = None) -> BeamResult | ContactResult | GraspResult:
    """Solve a scene (``kind: beam``, ``contact`` or ``grasp``) given as a
    file path or as the file's content (a mapping); with ``out``, also write
    result.json, the CSV tables and report.html there. ``progress(message)``
    is called as a long run goes.

    >>> r = simulate("beam_table_2_3.yaml")     # a shipped problem, by its name
    >>> r.status, r.cases, r.max_error_estimate_m < 1e-9
    (<Status.FINISHED: 'finished'>, 1, True)

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
    scene = load_scene(source)
    if isinstance(scene, DesignProblem):
        raise ValueError("design.simulate runs scenes; a design problem (kind: design) "
                         "runs with design.solve")
    with interrupt.handled():
        return finish(run(scene, source, progress), out)


def solve(source: str | Path | Mapping, out: str | Path | None = None,
          progress: Progress | None = None, *, workers: int | None = None,
          scheduler: str | None = None, resume: bool = False) -> DesignResult:
    """Optimise a design problem (``kind: design``, a path or the file's
    content), verify the optimum by an independent simulation at 4x finer
    resolution, and return the result (with ``out``, also write result.json,
    the CSV tables, ``optimum.yaml`` and ``report.html`` there).
    ``result.status`` says how it ended: ``VERIFIED``, ``NO_IMPROVEMENT``
    (the baseline is the answer), ``FAILED_VERIFICATION`` or ``ERROR``.

    The problem's cases run on ``workers`` local processes (None: one per
    core; 1: in this process, one after another) or on the Dask
    ``scheduler`` at ``tcp://HOST:PORT``; with ``out``, each finished case
    is kept in ``out/cases.sqlite`` and ``resume`` reuses them (see
    :mod:`design.study`). Raises :class:`~design.errors.StudyError`, before
    the run, if that store holds cases and ``resume`` is false, and
    :class:`~design.errors.ProblemFileError` for bad input (nothing written).
    examples/quickstart.py solves a two-variable problem in seconds; a
    scene is refused:

    >>> solve("beam_table_2_3.yaml")
    Traceback (most recent call last):
    ...
    ValueError: design.solve needs a design problem (kind: design); use design.simulate for scenes
    """
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
        return finish(run(scene, source, progress, study), out)


def fit(source: str | Path | Mapping, out: str | Path | None = None,
        progress: Progress | None = None) -> FitResult:
    """Run a fit problem (``kind: fit``, a path or the file's content):
    calibrate a finger's EI(s) or a belt's speed profile from measurements
    (with ``out``, also write the model file, result.json, the CSV tables
    and ``report.html`` there). Raises
    :class:`~design.errors.ProblemFileError` for bad input (nothing written).

    >>> belt = fit("examples/fit/belt_figure_5_10.yaml")    # from the checkout's root
    >>> belt.status, round(belt.to_dict()["fitted"]["final_speed"], 2)
    (<Status.FITTED: 'fitted'>, 0.25)
    """
    from design.report.fit import write_fit
    from design.run.fit import run as fit_run

    problem = load_fit(source)
    if out is not None:
        check_output_folder(Path(out))
    with interrupt.handled():
        output = fit_run(problem, progress)
        if not isinstance(source, Mapping):
            output.result["scene_file"] = str(source)
        return finish(output, out, write_fit)


def check(source: str | Path | Mapping) -> CheckResult:
    """Validate any input file (a scene, a design or fit problem, or a model
    file), a path or its content; the result's ``value`` is what it
    describes, or its ``problems`` say what is wrong (file, field, the
    accepted range).

    >>> bad = check({"kind": "beam", "finger": {"length": 0.2, "EI": 0.08},
    ...              "load": {"F": -1, "alpha": "90 deg"}})
    >>> bad.status, [str(p) for p in bad.problems]
    (<Status.INVALID: 'invalid'>, ['<scene>: load.F: -1 N is outside the accepted range [0, inf) N'])
    """
    try:
        kind, value = check_file(source)
    except ProblemFileError as exc:
        n = len(exc.problems)
        return CheckResult(status=Status.INVALID, problems=tuple(exc.problems),
                           message=f"{n} problem{'s' if n != 1 else ''} found")
    return CheckResult(status=Status.VALID, message="no problem found", kind=kind,
                       name=getattr(value, "name", "") or "", value=value)


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
