"""Reports: a self-contained ``report.html`` (figures embedded, also written
as PNG) for every run, built from its result and the runs behind it."""

from __future__ import annotations

from pathlib import Path

from design.io.results import output_files
from design.report.page import Page, write_report
from design.run import RunOutput


def build_report(output: RunOutput) -> Page:
    """The report of a finished run, by the kind of its scene."""
    from design.report.beam_contact import beam_page, contact_page
    from design.report.design import design_page
    from design.report.grasp import grasp_page
    from design.report.line import line_page

    r, a = output.result, output.artifacts
    if r["kind"] == "beam":
        return beam_page(r)
    if r["kind"] == "contact":
        return contact_page(r)
    if r["kind"] == "grasp":
        return grasp_page(r, a["run"])
    if "line" in r:
        return line_page(r, a["baseline"], a["optimum"])
    return design_page(r, a["baseline"], a["optimum"])


def write_run(out_dir: Path, output: RunOutput) -> list[Path]:
    """Write a run's result.json, tables and files, then its report and figures;
    every file atomically, the report last; then remove the files an earlier
    run in ``out_dir`` wrote and this one did not. Returns the paths written."""
    page = build_report(output)
    return write_report(out_dir, page, output_files(output.result, output.tables, output.files))
