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
import os
import sys
import time
from pathlib import Path

from design import __version__
from design.cli import EXIT_BAD_INPUT, EXIT_OK, _progress, _report_problems, output_folder
from design.errors import ProblemFileError
from design.io.beam_scene import BeamScene
from design.io.contact_scene import ContactScene
from design.io.design_problem import DesignProblem
from design.io.grasp_scene import GraspScene
from design.io.results import json_text
from design.io.scene import load_scene
from design.report.page import write_report
from design.tradeoff import beam, contact, grasp, optimiser, report
from design.tradeoff.study import choose, mark_front

#: scene type -> the study of its solver level
STUDIES = {BeamScene: beam.study, ContactScene: contact.study, GraspScene: grasp.study,
           DesignProblem: optimiser.study}


def cmd_tradeoff(args: argparse.Namespace) -> int:
    tolerance = args.tolerance
    if tolerance is not None and not (math.isfinite(tolerance) and tolerance > 0):
        print(f"error: --tolerance {tolerance:g}: a relative error > 0 (e.g. 0.01). "
              f"Nothing was written.", file=sys.stderr)
        return EXIT_BAD_INPUT
    try:
        scene = load_scene(args.scene)
    except ProblemFileError as exc:
        return _report_problems(exc)
    name = scene.name or Path(args.scene).stem
    out = output_folder(args.out, Path("reports") / f"{name}_tradeoff")
    if out is None:
        return EXIT_BAD_INPUT
    progress = None if args.quiet else _progress
    start, t0 = os.getloadavg(), time.perf_counter()
    study = STUDIES[type(scene)](scene, args.quick, progress)
    mark_front(study.rows)
    chosen = choose(study.rows, tolerance)
    meta = {"name": name, "scene": str(args.scene), "toolkit_version": __version__,
            "quick": bool(args.quick), "wall_time_s": time.perf_counter() - t0,
            "cores": os.cpu_count(),
            "loadavg": {"start": [round(v, 2) for v in start],
                        "end": [round(v, 2) for v in os.getloadavg()]}}
    data = report.result(study, chosen, tolerance, meta)
    files = {"tradeoff.json": json_text(data), "tradeoff.csv": report.csv_table(study)}
    page = report.page(study, data, chosen, tolerance)
    written = write_report(out, page, files)
    print(report.text_table(report.table_rows(study)))
    print()
    for line in data["verdicts"]:
        print(line)
    for path in written:
        print(path)
    return EXIT_OK
