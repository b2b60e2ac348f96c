"""The reproduction report (``design reproduce``): the thesis's reference
cases rerun and written as reproduction.json, reproduction.csv, report.html
and figures/*.png, every row a thesis number or claim against ours.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from pathlib import Path

from design import __version__
from design.io.results import csv_text, json_text
from design.report.page import Page, write_report
from design.reproduce import beam_rows, contact_rows, grasp_rows
from design.reproduce.rows import COLUMNS, CaseFailed, Section, tally, tally_by_basis, verdict

HOW_TO_READ = (
    "Each row sets a number or a claim of the thesis beside ours. A numeric row agrees when "
    "|ours - thesis| <= tolerance (in its unit); the tolerance is half a unit in the thesis's "
    "last printed digit, widened only where the thesis states a coarser accuracy (e.g. its "
    "contact solver's ERR = 0.5 mm), where its number is a reading of a plot, or where it "
    "depends on inputs it gives roughly or not at all; each section says which. A claim row (a "
    "trend or a bound) agrees when ours bears it out by the criterion in its explanation. The "
    "'basis' column says what ours is compared with, and the verdict counts each apart: a "
    "thesis measurement (the football experiment of §5.3: its rise and what its video shows), "
    "a thesis simulation (the thesis's own calculations and simulations; 'kind' says whether "
    "it printed a number or a statement), or, where it prints nothing, an own reference (a "
    "closed form, a finer method); no tolerance is derived from our own results. Context rows "
    "are shown and never counted: a quantity of ours beside a different one of the thesis's, "
    "or a reading the thesis leaves open (the pallet, the spread over unprinted settings). SI "
    "units: m, N, s, rad, N m^2 (the thesis's degrees converted). Disagreements are findings, "
    "not failures: their explanations say what we think causes them, or which candidate "
    "causes were measured and ruled out.")


def _chapters(quick: bool) -> list[tuple[str, Callable[..., list[Section]]]]:
    """(name, function of the progress callback returning the sections)."""
    chapters = [
        ("chapter II: Tables 2-1, 2-3 and 5-2",
         lambda progress: beam_rows.sections(beam_rows.compute())),
        ("chapter III: Tables 3-2, 3-3, 3-5 and 3-6",
         lambda progress: contact_rows.sections(contact_rows.compute())),
    ]
    if not quick:
        chapters.append((f"chapter V: grasp figures ({len(grasp_rows.setups())} runs, most with "
                         "the spatial finger model)", _grasp_sections))
    return chapters


def _grasp_sections(progress) -> list[Section]:
    """Chapter V's section; raises CaseFailed after building it if a run failed
    (its rows say which)."""
    runs = grasp_rows.compute(progress)
    built = grasp_rows.sections(runs)
    failed = grasp_rows.failures(runs)
    if failed:
        raise CaseFailed("; ".join(failed), built)
    return built


def compute_sections(quick: bool, progress=None) -> tuple[list[Section], list[str]]:
    """Every section that could be computed, and a message per chapter that could not."""
    sections, failures = [], []
    for name, build in _chapters(quick):
        t0 = time.perf_counter()
        if progress:
            progress(f"{name} ...")
        try:
            sections += build(progress)
        except CaseFailed as exc:  # some cases failed: the rest is reported
            sections += exc.sections
            failures.append(f"{name}: could not be computed: {type(exc).__name__}: {exc}")
        except Exception as exc:  # noqa: BLE001  (any solver error: report it, go on)
            failures.append(f"{name}: could not be computed: {type(exc).__name__}: {exc}")
        if progress:
            progress(f"{name}: {time.perf_counter() - t0:.1f} s")
    if quick:
        sections.append(Section("grasp", grasp_rows.TITLE, "Skipped (--quick): the grasp runs "
                                "take tens of minutes; run 'design reproduce' without --quick.",
                                []))
    return sections, failures


def build_page(sections: list[Section], failures: list[str], quick: bool,
               started: float) -> tuple[Page, float]:
    """The report (verdict banner, summary, one part per section, the run)
    and the wall time (s) since ``started`` (a time.perf_counter() value)."""
    rows = [r for s in sections for r in s.rows]
    agree, total = tally(rows)
    page = Page("Thesis reproduction: ours against the thesis's numbers")
    banner = verdict(rows)
    if quick:
        banner += " (--quick: grasp figures skipped)"
    if failures:
        banner += f"; {len(failures)} chapter(s) could not be computed"
    page.banner(banner, "failed" if failures else "passed" if agree == total else "neutral")
    page.section("Summary", "summary")
    page.text(HOW_TO_READ)
    for message in failures:
        page.text(message)
    counts = [(s.title, *tally(s.rows)) for s in sections if s.rows]
    page.table([{"section": t, "rows": n, "agree": k, "disagree": n - k} for t, k, n in counts],
               table_id="summary-table")
    for s in sections:
        page.section(s.title, s.anchor)
        page.text(s.text)
        if s.rows:
            page.table([r.as_dict() for r in s.rows], table_id=f"rows-{s.anchor}", digits=6)
        for name, caption, table in s.tables:
            page.table(table, caption, table_id=f"{s.anchor}-{name}", digits=4)
        for fig, name, caption in s.figures:
            page.figure(fig, name, caption)
    wall = time.perf_counter() - started
    page.section("Run", "run")
    page.text(f"design reproduce{' --quick' if quick else ''}, toolkit {__version__}, wall time "
              f"{wall:.1f} s. Data: reproduction.json, reproduction.csv (the same rows).")
    return page, wall


def reproduce(out: Path, quick: bool, progress=None) -> tuple[list[Path], str, bool]:
    """Run the reference cases and write the report to ``out``: the paths
    written, the verdict line, and whether every chapter was computed."""
    t0 = time.perf_counter()
    sections, failures = compute_sections(quick, progress)
    rows = [r for s in sections for r in s.rows]
    agree, total = tally(rows)
    page, wall = build_page(sections, failures, quick, t0)
    result = {"kind": "reproduction", "toolkit_version": __version__, "wall_time_s": wall,
              "quick": quick, "skipped": [grasp_rows.TITLE] if quick else [],
              "failures": failures, "agree": agree, "total": total,
              "by_basis": {b: {"agree": k, "total": n}
                           for b, (k, n) in tally_by_basis(rows).items()},
              "context_rows": sum(not r.counted for r in rows),
              "tables": {f"{s.anchor}-{name}": {"caption": caption, "rows": table}
                         for s in sections for name, caption, table in s.tables},
              "columns": list(COLUMNS),
              "rows": [r.as_dict() for r in rows]}
    files = {"reproduction.json": json_text(result),
             "reproduction.csv": csv_text([r.as_dict() for r in rows])}
    if progress:
        progress(f"writing {out}")
    written = write_report(out, page, files)
    return written, verdict(rows) + (f"; could not compute: {'; '.join(failures)}"
                                     if failures else ""), not failures
