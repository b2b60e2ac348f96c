"""The ``design`` command.

Exit status: 0 success; 1 the run finished but did not succeed (a case did
not converge, a verification failed, an error); 2 bad input (nothing was
written); 130 stopped by Ctrl-C (nothing was written, or every file was).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from design.errors import ProblemFileError, StudyError, StudyFailed
from design import __version__

EXIT_OK, EXIT_FAILED, EXIT_BAD_INPUT = 0, 1, 2
#: 128 + SIGINT: what a shell reports for a command stopped by Ctrl-C
EXIT_INTERRUPTED = 130


def _progress(message: str) -> None:
    print(f"[design] {message}", file=sys.stderr, flush=True)


def _report_problems(exc: ProblemFileError) -> int:
    for problem in exc.problems:
        print(f"error: {problem}", file=sys.stderr)
    n = len(exc.problems)
    print(f"{n} problem{'s' if n != 1 else ''} found; nothing was written.", file=sys.stderr)
    return EXIT_BAD_INPUT


def output_folder(given: str | None, default: Path) -> Path | None:
    """The run's output folder (``--out``, else ``default``), checked before
    the run starts; None, with the reason printed, when it cannot be written."""
    from design.io.results import OutputFolderError, check_output_folder

    out = Path(given) if given else default
    try:
        check_output_folder(out)
    except OutputFolderError as exc:
        print(f"error: {exc}. Nothing was written.", file=sys.stderr)
        return None
    return out


def default_folder(scene: object, source: str) -> Path:
    """A run's output folder when ``--out`` is not given: reports/<name>/,
    with the scene's name, else its file's."""
    return Path("reports") / (scene.name or Path(source).stem)


def speed_fraction(text: str) -> float:
    """``--speed``: a playback speed in (0, 10], a fraction of real time."""
    try:
        value = float(text)
    except ValueError:
        value = 0.0
    if not 0.0 < value <= 10.0:
        raise argparse.ArgumentTypeError(f"a fraction of real time in (0, 10], not {text!r}. "
                                         f"Nothing was written")
    return value


def workers_count(text: str) -> int:
    """``--workers``: an integer >= 1."""
    try:
        n = int(text)
    except ValueError:
        n = 0
    if n < 1:
        raise argparse.ArgumentTypeError(
            f"an integer >= 1 (1 runs the cases in this process, one after another; "
            f"leave it out for one worker per core), not {text!r}. Nothing was written")
    return n


def scheduler_address(text: str) -> str:
    """``--scheduler``: a Dask scheduler's address, ``tcp://HOST:PORT``."""
    if "://" not in text:
        raise argparse.ArgumentTypeError(f"a Dask scheduler's address such as "
                                         f"tcp://HOST:8786, not {text!r}. Nothing was written")
    return text


def cmd_simulate(args: argparse.Namespace) -> int:
    from design.api import run
    from design.io.design_problem import DesignProblem
    from design.report import write_run
    from design.io.scene import load_scene
    from design.study.cases import StudyOptions
    from design.study.store import STORE, check_store

    try:
        scene = load_scene(args.scene)
    except ProblemFileError as exc:
        return _report_problems(exc)
    if (args.command == "solve") != isinstance(scene, DesignProblem):
        wanted = "a design problem (kind: design)" if args.command == "solve" else "a scene"
        other = "design simulate" if args.command == "solve" else "design solve"
        print(f"error: {args.scene}: kind: 'design {args.command}' needs {wanted}; use "
              f"'{other}' for this file. Nothing was written.", file=sys.stderr)
        return EXIT_BAD_INPUT
    out = output_folder(args.out, default_folder(scene, args.scene))
    if out is None:
        return EXIT_BAD_INPUT
    study = None
    try:
        if args.command == "solve":
            study = StudyOptions(workers=args.workers, scheduler=args.scheduler,
                                 resume=args.resume, store=out / STORE)
            check_store(study.store, args.resume)
        output = run(scene, args.scene, None if args.quiet else _progress, study)
    except StudyError as exc:
        print(f"error: {exc}. Nothing was written.", file=sys.stderr)
        return EXIT_BAD_INPUT
    except StudyFailed as exc:
        print(f"FAILED: {exc}. No result was written; the finished cases are in "
              f"{study.store}, and --resume runs the failed ones again.", file=sys.stderr)
        return EXIT_FAILED
    written = write_run(out, output)
    for path in written:
        print(path)
    r = output.result
    if r.get("kind") == "design":
        from design.run.solve import status_line

        print(status_line(r))
    elif r.get("kind") == "grasp" and output.ok:
        from design.run.grasp import summary_line

        print(summary_line(r))
    if not output.ok:
        if output.result.get("kind") == "design":
            print(f"FAILED: {output.result['status']}: {output.result['message']}",
                  file=sys.stderr)
        elif output.result.get("kind") == "grasp":
            print(f"FAILED: {output.result['summary']['message']}", file=sys.stderr)
        else:
            print("warning: not every case converged; see 'converged' and 'message' in "
                  "result.json", file=sys.stderr)
        return EXIT_FAILED
    return EXIT_OK


def cmd_check(args: argparse.Namespace) -> int:
    from design.api import check

    status = EXIT_OK
    for path in args.files:
        try:
            check(path)
            print(f"{path}: OK")
        except ProblemFileError as exc:
            for problem in exc.problems:
                print(f"error: {problem}", file=sys.stderr)
            status = EXIT_BAD_INPUT
    return status


def cmd_examples(args: argparse.Namespace) -> int:
    """List the shipped problems, each as the command that runs it by name."""
    from design.io.files import PROBLEMS
    from design.io.scene import examples

    print(f"Shipped problems, in {PROBLEMS}. Each runs by its name from any folder "
          f"(a file of that name in the working folder comes first):")
    for path, kind, summary in examples():
        print(f"\n  design {'solve' if kind == 'design' else 'simulate'} {path.name}\n"
              f"      {summary}")
    return EXIT_OK


def _lazy(module: str, name: str):
    """A command's function, imported only when the command runs."""
    def command(args: argparse.Namespace) -> int:
        import importlib

        return getattr(importlib.import_module(module), name)(args)
    return command


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="design", description="Optimal design and timing of compliant graspers.")
    parser.add_argument("--version", action="version", version=f"design {__version__}")
    sub = parser.add_subparsers(dest="command", required=True)
    p = sub.add_parser("simulate", help="solve a scene file and write its results")
    p.add_argument("scene", help="scene file (YAML)")
    p.add_argument("--out", help="output folder (default: reports/<scene name>/)")
    p.add_argument("--quiet", action="store_true", help="no progress messages")
    p.set_defaults(func=cmd_simulate)
    p = sub.add_parser("solve", help="optimise a design problem, verify it, write its results")
    p.add_argument("scene", help="design problem file (YAML, kind: design)")
    p.add_argument("--out", help="output folder (default: reports/<problem name>/)")
    p.add_argument("--quiet", action="store_true", help="no progress messages")
    p.add_argument("--workers", type=workers_count, metavar="N",
                   help="worker processes for the problem's cases (default: one per core; "
                   "1: in this process, one after another)")
    p.add_argument("--scheduler", type=scheduler_address, metavar="tcp://HOST:PORT",
                   help="run the cases on this Dask scheduler's workers (default: "
                   "$DASK_SCHEDULER_ADDRESS when --workers is not given)")
    p.add_argument("--resume", action="store_true",
                   help="reuse the finished cases in <out>/cases.sqlite, run only the rest")
    p.set_defaults(func=cmd_simulate)
    p = sub.add_parser("cases", help="list the cases a design solve stored "
                       "(<out>/cases.sqlite): status, hold, peak, wall time, worker")
    p.add_argument("source", metavar="PROBLEM_OR_DB",
                   help="design problem file (its output folder's store) or a cases.sqlite")
    p.add_argument("--out", help="the problem's output folder (default: reports/<problem name>/)")
    p.add_argument("--json", action="store_true", help="print the rows as JSON")
    p.set_defaults(func=_lazy("design.study.command", "cmd_cases"))
    p = sub.add_parser("tradeoff", help="measure error against wall time for every solver "
                       "level and resolution; pick the cheapest setting that meets a tolerance")
    p.add_argument("scene", help="scene or design problem file (YAML)")
    p.add_argument("--tolerance", type=float,
                   help="the accuracy wanted, relative to the finest reference (e.g. 0.01)")
    p.add_argument("--out", help="output folder (default: reports/<name>_tradeoff/)")
    p.add_argument("--quick", action="store_true", help="fewer resolutions and repetitions")
    p.add_argument("--quiet", action="store_true", help="no progress messages")
    p.set_defaults(func=_lazy("design.tradeoff.command", "cmd_tradeoff"))
    p = sub.add_parser("reproduce", help="rerun the thesis's reference cases and write a "
                       "reproduction report (thesis number, ours, difference, why)")
    p.add_argument("--out", help="output folder (default: reports/reproduction/)")
    p.add_argument("--quick", action="store_true", help="skip the slow grasp figures")
    p.add_argument("--quiet", action="store_true", help="no progress messages")
    p.set_defaults(func=_lazy("design.reproduce.command", "cmd_reproduce"))
    p = sub.add_parser("fit", help="calibrate a finger's EI(s) or a belt's speed profile "
                       "from measurements; write the model file and a report")
    p.add_argument("file", help="fit problem file (YAML, kind: fit)")
    p.add_argument("--out", help="output folder (default: reports/<problem name>/)")
    p.add_argument("--quiet", action="store_true", help="no progress messages")
    p.set_defaults(func=_lazy("design.fit.command", "cmd_fit"))
    p = sub.add_parser("animate", help="write a grasp or design run's 3-D animation from its "
                       "result folder: MP4 (with ffmpeg) or GIF, or the interactive HTML view")
    p.add_argument("result_dir", metavar="RESULT_DIR", help="a run's output folder (its "
                   "result.json)")
    p.add_argument("--out", metavar="FILE", help="FILE.mp4, FILE.gif or FILE.html (default: "
                   "RESULT_DIR/animation.mp4, or .gif without ffmpeg)")
    p.add_argument("--speed", type=speed_fraction, default=0.25,
                   help="a video's playback speed, a fraction of real time (default 0.25)")
    p.add_argument("--quiet", action="store_true", help="no progress messages")
    p.set_defaults(func=_lazy("design.report.animate", "cmd_animate"))
    p = sub.add_parser("check", help="validate input files and report every problem")
    p.add_argument("files", nargs="+", help="scene, problem or model files (YAML)")
    p.set_defaults(func=cmd_check)
    p = sub.add_parser("examples", help="list the shipped problems, each with its description")
    p.set_defaults(func=cmd_examples)
    return parser


def main(argv: list[str] | None = None) -> int:
    from design import interrupt

    args = build_parser().parse_args(argv)
    try:
        with interrupt.handled():
            return args.func(args)
    except BaseException as exc:      # whatever the Ctrl-C became on its way out
        stopped = interrupt.stopped(exc)
        if stopped is None:
            raise
        print(stopped, file=sys.stderr)
        return EXIT_INTERRUPTED


if __name__ == "__main__":
    sys.exit(main())
