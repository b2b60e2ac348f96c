"""``design simulate``, ``design solve``, ``design check`` and ``design examples``."""

from __future__ import annotations

import argparse
import sys

from design.cli.common import (EXIT_BAD_INPUT, EXIT_FAILED, EXIT_OK, EXIT_STATUS, closing,
                               default_folder, output_folder, progress, report_problems)
from design.errors import ProblemFileError, StudyError, StudyFailed


def cmd_run(args: argparse.Namespace) -> int:
    """``design simulate SCENE`` or ``design solve PROBLEM``: run, write, say how it ended."""
    from design.api import finish, run
    from design.io.design_problem import DesignProblem
    from design.io.scene import load_scene
    from design.study.cases import StudyOptions
    from design.study.store import STORE, check_store

    try:
        scene = load_scene(args.scene)
    except ProblemFileError as exc:
        return report_problems(exc)
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
        output = run(scene, args.scene, None if args.quiet else progress, study)
    except StudyError as exc:
        print(f"error: {exc}. Nothing was written.", file=sys.stderr)
        return EXIT_BAD_INPUT
    except StudyFailed as exc:
        print(f"FAILED: {exc}. No result was written; the finished cases are in "
              f"{study.store}, and --resume runs the failed ones again.", file=sys.stderr)
        return EXIT_FAILED
    return closing(finish(output, out))


def cmd_check(args: argparse.Namespace) -> int:
    """``design check FILE...``: every file checked, every problem printed."""
    from design.api import check

    worst = EXIT_OK
    for path in args.files:
        result = check(path)
        if result.success:
            print(f"{path}: OK")
        for problem in result.problems:
            print(f"error: {problem}", file=sys.stderr)
        worst = max(worst, EXIT_STATUS[result.status])
    return worst


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
