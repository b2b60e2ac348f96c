"""The ``design`` command: one sub-command per module of this package.

Exit status: 0 success; 1 the run finished but did not succeed (a case did
not converge, a grasp stopped early, a verification failed, an error, a fit
that did not succeed); 2 bad input (nothing was written); 130 stopped by
Ctrl-C (nothing was written, or every file was). A run's status maps to its
exit status through one table, :data:`design.cli.common.EXIT_STATUS`.
"""

from __future__ import annotations

import argparse
import sys

from design import __version__
from design.cli.common import EXIT_INTERRUPTED, scheduler_url, speed_fraction, workers_count


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
    p.set_defaults(func=_lazy("design.cli.run", "cmd_run"))
    p = sub.add_parser("solve", help="optimise a design problem, verify it, write its results")
    p.add_argument("scene", help="design problem file (YAML, kind: design)")
    p.add_argument("--out", help="output folder (default: reports/<problem name>/)")
    p.add_argument("--quiet", action="store_true", help="no progress messages")
    p.add_argument("--workers", type=workers_count, metavar="N",
                   help="worker processes for the problem's cases (default: one per core; "
                   "1: in this process, one after another)")
    p.add_argument("--scheduler", type=scheduler_url, metavar="tcp://HOST:PORT",
                   help="run the cases on this Dask scheduler's workers (default: "
                   "$DASK_SCHEDULER_ADDRESS when --workers is not given)")
    p.add_argument("--resume", action="store_true",
                   help="reuse the finished cases in <out>/cases.sqlite, run only the rest")
    p.set_defaults(func=_lazy("design.cli.run", "cmd_run"))
    p = sub.add_parser("cases", help="list the cases a design solve stored "
                       "(<out>/cases.sqlite): status, hold, peak, wall time, worker")
    p.add_argument("source", metavar="PROBLEM_OR_DB",
                   help="design problem file (its output folder's store) or a cases.sqlite")
    p.add_argument("--out", help="the problem's output folder (default: reports/<problem name>/)")
    p.add_argument("--json", action="store_true", help="print the rows as JSON")
    p.set_defaults(func=_lazy("design.cli.cases", "cmd_cases"))
    p = sub.add_parser("tradeoff", help="measure error against wall time for every solver "
                       "level and resolution; pick the cheapest setting that meets a tolerance")
    p.add_argument("scene", help="scene or design problem file (YAML)")
    p.add_argument("--tolerance", type=float,
                   help="the accuracy wanted, relative to the finest reference (e.g. 0.01)")
    p.add_argument("--out", help="output folder (default: reports/<name>_tradeoff/)")
    p.add_argument("--quick", action="store_true", help="fewer resolutions and repetitions")
    p.add_argument("--quiet", action="store_true", help="no progress messages")
    p.set_defaults(func=_lazy("design.cli.tradeoff", "cmd_tradeoff"))
    p = sub.add_parser("reproduce", help="rerun the thesis's reference cases and write a "
                       "reproduction report (thesis number, ours, difference, why)")
    p.add_argument("--out", help="output folder (default: reports/reproduction/)")
    p.add_argument("--quick", action="store_true", help="skip the slow grasp figures")
    p.add_argument("--quiet", action="store_true", help="no progress messages")
    p.set_defaults(func=_lazy("design.cli.reproduce", "cmd_reproduce"))
    p = sub.add_parser("fit", help="calibrate a finger's EI(s) or a belt's speed profile "
                       "from measurements; write the model file and a report")
    p.add_argument("file", help="fit problem file (YAML, kind: fit)")
    p.add_argument("--out", help="output folder (default: reports/<problem name>/)")
    p.add_argument("--quiet", action="store_true", help="no progress messages")
    p.set_defaults(func=_lazy("design.cli.fit", "cmd_fit"))
    p = sub.add_parser("animate", help="write a grasp or design run's 3-D animation from its "
                       "result folder: MP4 (with ffmpeg) or GIF, or the interactive HTML view")
    p.add_argument("result_dir", metavar="RESULT_DIR", help="a run's output folder (its "
                   "result.json)")
    p.add_argument("--out", metavar="FILE", help="FILE.mp4, FILE.gif or FILE.html (default: "
                   "RESULT_DIR/animation.mp4, or .gif without ffmpeg)")
    p.add_argument("--speed", type=speed_fraction, default=0.25,
                   help="a video's playback speed, a fraction of real time (default 0.25)")
    p.add_argument("--quiet", action="store_true", help="no progress messages")
    p.set_defaults(func=_lazy("design.cli.animate", "cmd_animate"))
    p = sub.add_parser("check", help="validate input files and report every problem")
    p.add_argument("files", nargs="+", help="scene, problem or model files (YAML)")
    p.set_defaults(func=_lazy("design.cli.run", "cmd_check"))
    p = sub.add_parser("examples", help="list the shipped problems, each with its description")
    p.set_defaults(func=_lazy("design.cli.run", "cmd_examples"))
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
