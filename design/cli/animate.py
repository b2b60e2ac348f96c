"""``design animate RESULT_DIR``: a grasp or design run's animation on its
own (design/report/animate.py). Exit status: 0 written; 2 a result or
output that will not do, nothing written."""

from __future__ import annotations

import argparse
import sys

from design.cli.common import EXIT_BAD_INPUT, EXIT_OK, progress


def cmd_animate(args: argparse.Namespace) -> int:
    from design.report.animate import AnimateError, animate

    try:
        path = animate(args.result_dir, args.out, args.speed, None if args.quiet else progress)
    except AnimateError as exc:
        print(f"error: {exc}. Nothing was written.", file=sys.stderr)
        return EXIT_BAD_INPUT
    print(path)
    return EXIT_OK
