"""``design reproduce``: rerun the thesis's reference cases and write the
reproduction report (design/reproduce/report.py).

Exit status: 0 every case computed; 1 a case could not be computed (the
report is still written, saying which); 2 the output folder cannot be
written (checked before the first case runs).
"""

from __future__ import annotations

import argparse
from pathlib import Path

from design.cli.common import EXIT_BAD_INPUT, EXIT_FAILED, EXIT_OK, output_folder, progress


def cmd_reproduce(args: argparse.Namespace) -> int:
    """Run the reference cases, write the report; print the paths written."""
    from design.reproduce.report import reproduce

    out = output_folder(args.out, Path("reports") / "reproduction")
    if out is None:
        return EXIT_BAD_INPUT
    written, verdict, complete = reproduce(out, args.quick, None if args.quiet else progress)
    for path in written:
        print(path)
    print(verdict)
    return EXIT_OK if complete else EXIT_FAILED
