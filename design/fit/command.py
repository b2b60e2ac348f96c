"""``design fit FILE``: calibrate a finger or a belt model from measurements.

Writes the model (``finger.yaml`` or ``conveyor.yaml``), ``result.json``,
CSV tables, ``report.html`` and its figures to ``reports/<name>/`` (or
``--out``), all rendered in memory before the first is written. Exit
status: 0 done; 1 the fit did not succeed (Ipopt failed, or the model file
would not read back); 2 bad input, nothing written.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from design.cli import EXIT_BAD_INPUT, EXIT_FAILED, EXIT_OK, _progress, _report_problems, \
    output_folder
from design.errors import ProblemFileError
from design.io.scene import load_fit
from design.report.fit import write_fit
from design.run.fit import run


def cmd_fit(args: argparse.Namespace) -> int:
    try:
        problem = load_fit(args.file)
    except ProblemFileError as exc:
        return _report_problems(exc)
    out = output_folder(args.out, Path("reports") / problem.name)
    if out is None:
        return EXIT_BAD_INPUT
    output = run(problem, None if args.quiet else _progress)
    output.result["scene_file"] = str(args.file)
    for path in write_fit(out, output):
        print(path)
    r = output.result
    if r["target"] == "finger":
        print(f"{r['name']}: EI(s) by the {r['method']} model, "
              f"{len(r['warnings'])} warning(s); model: {out / 'finger.yaml'}")
    else:
        f = r["fitted"]
        print(f"{r['name']}: belt {f['speed']:.4g} m/s"
              + (f" slowing to {f['final_speed']:.4g} m/s at {f['rate']:.3g} m/s^2 from "
                 f"t = {f['start_time']:.4g} s" if r["decelerates"] else " (constant)")
              + f"; model: {out / 'conveyor.yaml'}")
    for warning in r["warnings"]:
        print(f"warning: {warning}", file=sys.stderr)
    return EXIT_OK if output.ok else EXIT_FAILED
