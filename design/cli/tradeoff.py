"""``design tradeoff SCENE``: measure, print, write.

Writes ``tradeoff.json``, ``tradeoff.csv``, ``report.html`` and
``figures/<level>_tradeoff.png`` to ``reports/<name>_tradeoff/`` (or
``--out``), all rendered in memory before the first is written. Exit status:
0 done (whether or not a setting meets the tolerance: the output says);
2 bad input, nothing written.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

from design.cli.common import EXIT_BAD_INPUT, EXIT_OK, output_folder, progress, report_problems
from design.errors import ProblemFileError


def cmd_tradeoff(args: argparse.Namespace) -> int:
    from design.io.scene import load_scene
    from design.report.page import write_report
    from design.tradeoff.run import tradeoff

    tolerance = args.tolerance
    if tolerance is not None and not (math.isfinite(tolerance) and tolerance > 0):
        print(f"error: --tolerance {tolerance:g}: a relative error > 0 (e.g. 0.01). "
              f"Nothing was written.", file=sys.stderr)
        return EXIT_BAD_INPUT
    try:
        scene = load_scene(args.scene)
    except ProblemFileError as exc:
        return report_problems(exc)
    name = scene.name or Path(args.scene).stem
    out = output_folder(args.out, Path("reports") / f"{name}_tradeoff")
    if out is None:
        return EXIT_BAD_INPUT
    data, files, page, table = tradeoff(scene, args.scene, args.quick, tolerance,
                                        None if args.quiet else progress)
    written = write_report(out, page, files)
    print(table)
    print()
    for line in data["verdicts"]:
        print(line)
    for path in written:
        print(path)
    return EXIT_OK
