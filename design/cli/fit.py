"""``design fit FILE``: calibrate a finger or a belt model from measurements.

Writes the model (``finger.yaml`` or ``conveyor.yaml``), ``result.json``,
CSV tables, ``report.html`` and its figures to ``reports/<name>/`` (or
``--out``), all rendered in memory before the first is written. Exit
status: 0 fitted; 1 the fit did not succeed (the solver failed, or the
model file would not read back); 2 bad input, nothing written.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from design.cli.common import EXIT_BAD_INPUT, closing, output_folder, progress, report_problems
from design.errors import ProblemFileError


def cmd_fit(args: argparse.Namespace) -> int:
    from design.api import finish
    from design.io.scene import load_fit
    from design.report.fit import write_fit
    from design.run.fit import run

    try:
        problem = load_fit(args.file)
    except ProblemFileError as exc:
        return report_problems(exc)
    out = output_folder(args.out, Path("reports") / problem.name)
    if out is None:
        return EXIT_BAD_INPUT
    output = run(problem, None if args.quiet else progress)
    output.result["scene_file"] = str(args.file)
    result = finish(output, out, write_fit)
    code = closing(result)
    for warning in result.warnings:
        print(f"warning: {warning}", file=sys.stderr)
    return code
