"""A study's outputs, rendered in memory: the table (text, CSV, HTML),
tradeoff.json, the verdict lines and the error-against-wall-time figure."""

from __future__ import annotations

import math

import matplotlib.pyplot as plt

from design.io.results import csv_text
from design.report.page import Page, number
from design.tradeoff.study import Row, Study


def table_rows(study: Study) -> list[dict]:
    """One flat row per setting: the columns of the printed, CSV and HTML tables
    (errors relative, dimensionless; times in s)."""
    return [{"level": r.level, "method": r.method, "setting": r.label, "error": r.error,
             **{f"{m}_error": r.errors[m] for m in study.metrics},
             "wall_time_s": r.wall_time_s, "first_run_s": r.first_run_s,
             "is_default": r.is_default, "is_reference": r.is_reference,
             "converged": r.converged, "on_front": r.on_front,
             "meets_tolerance": r.meets_tolerance} for r in study.rows]


def text_table(rows: list[dict]) -> str:
    """The table as aligned text, cells formatted as in the HTML report."""
    cells = [list(rows[0])] + [[number(v) for v in r.values()] for r in rows]
    widths = [max(len(row[i]) for row in cells) for i in range(len(cells[0]))]
    return "\n".join("  ".join(c.rjust(w) if i > 2 else c.ljust(w)
                               for i, (c, w) in enumerate(zip(row, widths))).rstrip()
                     for row in cells)


def describe(row: Row) -> str:
    return f"{row.label} (error {row.error:.3g}, {row.wall_time_s:.3g} s)"


def verdicts(study: Study, chosen: Row | None, tolerance: float | None) -> list[str]:
    """What the study found, one sentence each: the tolerance's choice, whether
    the default is on the front, the scene's own setting."""
    usable = [r for r in study.rows if r.usable]
    if tolerance is None:
        lines = ["no --tolerance given: pick a setting from the Pareto front"]
    elif chosen is not None:
        lines = [f"cheapest setting meeting the tolerance {tolerance:g}: {describe(chosen)}"]
    else:
        best = min(usable, key=lambda r: r.error, default=None)
        lines = [f"no setting meets the tolerance {tolerance:g}" +
                 (f"; the most accurate is {describe(best)}" if best else "")]
    d = study.default
    if d.on_front:
        lines.append(f"the toolkit's default, {describe(d)}, is on the Pareto front")
    else:
        why = f": {d.note or 'it did not converge'}" if not d.usable else \
            next(f": {describe(o)} is at least as fast and as accurate" for o in usable
                 if o.on_front and o.wall_time_s <= d.wall_time_s and o.error <= d.error)
        lines.append(f"the toolkit's default, {describe(d)}, is NOT on the Pareto front{why}")
    own = next((r for r in study.rows if r.setting == study.scene_setting), None)
    if own is None:
        lines.append("the scene's own solver setting is not among the settings studied")
    elif not own.is_default:
        lines.append(f"the scene's own setting, {describe(own)}, is "
                     f"{'on' if own.on_front else 'NOT on'} the Pareto front")
    return lines


def result(study: Study, chosen: Row | None, tolerance: float | None, meta: dict) -> dict:
    """The content of tradeoff.json."""
    rows = [{"level": r.level, "method": r.method, "label": r.label, "setting": r.setting,
             "errors": r.errors, "error": r.error, "values": r.values,
             "wall_time_s": r.wall_time_s, "first_run_s": r.first_run_s,
             "is_default": r.is_default, "is_reference": r.is_reference,
             "converged": r.converged, "on_front": r.on_front,
             "meets_tolerance": r.meets_tolerance, "note": r.note} for r in study.rows]
    return {"kind": "tradeoff", "level": study.level, **meta,
            "units": {"error": "relative (dimensionless)", "time": "s"},
            "metrics": study.metrics, "tolerance": tolerance,
            "chosen": None if chosen is None else {"label": chosen.label,
                                                   "setting": chosen.setting,
                                                   "error": chosen.error,
                                                   "wall_time_s": chosen.wall_time_s},
            "default": {"label": study.default.label, "setting": study.default.setting,
                        "on_front": study.default.on_front},
            "scene_setting": study.scene_setting, "reference": study.reference,
            "notes": study.notes, "verdicts": verdicts(study, chosen, tolerance),
            "rows": rows}


def figure(study: Study, chosen: Row | None, tolerance: float | None):
    """Relative error against wall time, log-log: every setting by method, the
    Pareto front joined, the default and the chosen setting marked. Errors of
    exactly 0 (the reference) are drawn on the bottom edge."""
    plotted = [r for r in study.rows if math.isfinite(r.error)]
    positive = [r.error for r in plotted if r.error > 0]
    floor = min(positive, default=1e-16) / 10

    def y(r: Row) -> float:
        return max(r.error, floor)

    fig, ax = plt.subplots(figsize=(8, 5.5))
    for i, method in enumerate(dict.fromkeys(r.method for r in plotted)):
        mine = sorted((r for r in plotted if r.method == method), key=lambda r: -r.error)
        ok = [r for r in mine if r.converged]
        ax.plot([r.wall_time_s for r in ok], [y(r) for r in ok], marker="osD^vP"[i % 6],
                ls=":", color=f"C{i}", label=method)
        bad = [r for r in mine if not r.converged]
        if bad:
            ax.plot([r.wall_time_s for r in bad], [y(r) for r in bad], marker="osD^vP"[i % 6],
                    ls="none", mfc="none", color=f"C{i}", label=f"{method} (not converged)")
        for r in mine:
            ax.annotate(r.label.removeprefix(method).strip() or r.label,
                        (r.wall_time_s, y(r)), fontsize=7, xytext=(4, 3),
                        textcoords="offset points")
    front = sorted((r for r in plotted if r.on_front), key=lambda r: r.wall_time_s)
    ax.plot([r.wall_time_s for r in front], [y(r) for r in front], color="k", lw=2.5,
            alpha=0.35, zorder=0, label="Pareto front")
    d = study.default
    if math.isfinite(d.error):
        ax.plot(d.wall_time_s, y(d), marker="*", ms=18, mfc="none", mec="red", mew=1.5,
                ls="none", label=f"toolkit default ({'on' if d.on_front else 'not on'} front)")
    if chosen is not None:
        ax.plot(chosen.wall_time_s, y(chosen), marker="o", ms=16, mfc="none", mec="green",
                mew=2, ls="none", label="cheapest meeting the tolerance")
    if tolerance is not None:
        ax.axhline(tolerance, color="green", ls="--", lw=1, label=f"tolerance {tolerance:g}")
    if any(r.error == 0 for r in plotted):
        ax.axhline(floor, color="grey", lw=0.8)
        ax.text(0.01, 0.02, "bottom line: error 0 (the reference itself)", fontsize=7,
                transform=ax.transAxes, color="grey")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("wall time (s)")
    ax.set_ylabel("relative error (largest of: " + ", ".join(study.metrics) + ")")
    ax.set_title(f"{study.level}: error against wall time")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7, loc="best")
    return fig


def page(study: Study, data: dict, chosen: Row | None, tolerance: float | None) -> Page:
    """report.html: the verdict, the table, the figure, the reference and the run."""
    p = Page(f"Speed against accuracy: {data['name']} ({study.level})")
    kind = "neutral" if tolerance is None else "passed" if chosen is not None else "failed"
    p.banner(data["verdicts"][0], kind)
    for line in data["verdicts"][1:]:
        p.text(line)
    p.section("Settings", "settings")
    p.text("Error: " + "; ".join(f"{m}: {text}" for m, text in study.metrics.items()) +
           f". 'error' is the largest of these. Reference: {study.reference['what']}.")
    scalars = {k: v for k, v in study.reference.items()
               if isinstance(v, (int, float)) and not isinstance(v, bool)}
    p.text("The reference's numbers: " + ", ".join(f"{k} {number(v)}"
                                                   for k, v in scalars.items()) + ".")
    for note in study.notes:
        p.text(note)
    p.table(table_rows(study), caption="every setting studied", table_id="tradeoff")
    p.section("Error against wall time", "figure")
    p.figure(figure(study, chosen, tolerance), f"{study.level}_tradeoff",
             f"{study.level}: relative error against wall time (log-log), the Pareto front "
             f"in grey, the toolkit's default starred")
    p.section("Run", "run")
    p.text(f"toolkit {data['toolkit_version']}; {'quick' if data['quick'] else 'full'} study; "
           f"load average (1, 5, 15 min) at the start {data['loadavg']['start']} and the end "
           f"{data['loadavg']['end']} on {data['cores']} cores: wall times include the effect "
           f"of whatever else ran on the machine")
    return p


def csv_table(study: Study) -> str:
    return csv_text(table_rows(study))
