"""A tradeoff study of a scene or design problem: its level's settings
measured, the cheapest setting that meets a tolerance chosen, and the files
rendered in memory (tradeoff.json, tradeoff.csv, the report page) for
``design tradeoff`` (design/cli/tradeoff.py) to write.
"""

from __future__ import annotations

import os
import time
from pathlib import Path

from design import __version__
from design.io.beam_scene import BeamScene
from design.io.contact_scene import ContactScene
from design.io.design_problem import DesignProblem
from design.io.grasp_scene import GraspScene
from design.io.results import json_text
from design.report.page import Page
from design.tradeoff import beam, contact, grasp, optimiser, report
from design.tradeoff.study import choose, mark_front

#: scene type -> the study of its solver level
STUDIES = {BeamScene: beam.study, ContactScene: contact.study, GraspScene: grasp.study,
           DesignProblem: optimiser.study}


def tradeoff(scene: object, source: str, quick: bool, tolerance: float | None,
             progress=None) -> tuple[dict, dict[str, str], Page, str]:
    """Study ``scene`` (read from ``source``) at its level: the result
    (tradeoff.json's content), the files rendered (name -> text), the
    report page and the table as text."""
    name = scene.name or Path(source).stem
    start, t0 = os.getloadavg(), time.perf_counter()
    study = STUDIES[type(scene)](scene, quick, progress)
    mark_front(study.rows)
    chosen = choose(study.rows, tolerance)
    meta = {"name": name, "scene": str(source), "toolkit_version": __version__,
            "quick": bool(quick), "wall_time_s": time.perf_counter() - t0,
            "cores": os.cpu_count(),
            "loadavg": {"start": [round(v, 2) for v in start],
                        "end": [round(v, 2) for v in os.getloadavg()]}}
    data = report.result(study, chosen, tolerance, meta)
    files = {"tradeoff.json": json_text(data), "tradeoff.csv": report.csv_table(study)}
    page = report.page(study, data, chosen, tolerance)
    return data, files, page, report.text_table(report.table_rows(study))
