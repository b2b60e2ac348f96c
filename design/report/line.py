"""The report of a line-speed run (``design solve`` of ``objective: throughput``)."""

from __future__ import annotations

from matplotlib.figure import Figure

from design.report.grasp import grasp_figures
from design.report.page import Page
from design.solvers.grasp.simulation import GraspRun


def pareto_figure(result: dict) -> Figure:
    """Every design the searches simulated, worst hold against rate, the
    front (rate, worst hold, peak: none better in all three) coloured by
    peak force; the thesis's and the kill line's rates, the hold asked and
    the answer marked."""
    line, front = result["line"], result["pareto"]
    fig = Figure(figsize=(9, 5))
    ax = fig.subplots()
    ax.axvline(line["thesis_rate_per_min"], color="0.5", ls="--")
    ax.axvline(line["kill_line_rate_per_min"], color="0.2", ls="--")
    ax.axhline(result["objective"]["min_hold_s"], color="tab:red", ls=":",
               label=f"hold asked ({result['objective']['min_hold_s']:g} s)")
    top = ax.get_ylim()[1]
    if front:
        points = ax.scatter([r["line_rate_per_min"] for r in front],
                            [r["hold_time_s"] for r in front],
                            c=[r["max_finger_force_N"] for r in front], cmap="viridis", s=30,
                            label="front: rate, worst hold, peak")
        fig.colorbar(points, ax=ax, label="peak finger force (N)")
        top = max(r["hold_time_s"] for r in front)
    for x, words in ((line["thesis_rate_per_min"], "thesis"),
                     (line["kill_line_rate_per_min"], "kill line")):
        ax.text(x, top, f" {words} ({x:g}/min)", rotation=90, va="top", fontsize=8)
    if result["status"] in ("verified", "no improvement found"):
        ax.plot(result["line_rate_per_min"], result["verification"]["hold_time_s"], "r*",
                ms=14, label="answer (verified)")
    ax.set_xlabel("line rate (birds/min)")
    ax.set_ylabel("worst bird's N = 0 hold (s)")
    ax.legend(loc="lower left", fontsize=8)
    return fig


def line_page(result: dict, baseline: GraspRun, optimum: GraspRun) -> Page:
    line = result["line"]
    page = Page(f"Line speed: {result['name']}")
    kind = "passed" if result["status"] == "verified" else \
        "neutral" if result["status"] == "no improvement found" else "failed"
    page.banner(f"{result['status']}: {result['message']}", kind)
    if result.get("description"):
        page.text(result["description"])
    page.section("Rate by number of finger sets", "sets")
    page.text("Each number of finger sets is a case: the pattern search raises the rate "
              "(birds/min = 60 n omega / 2 pi) with every bird held at least "
              f"{result['objective']['min_hold_s']:g} s under the {result['cap']['N']:.2f} N "
              "cap, no finger past its fold force and no bird jammed; its answer is "
              "simulated again at 4x finer resolution. What limits the answer: "
              f"{line['limit']}.")
    page.table([{k: r[k] for k in ("finger_sets", "status", "line_rate_per_min",
                                   "drum_speed_rpm", "belt_speed_m_s", "bird_spacing_m",
                                   "worst_hold_time_s", "max_finger_force_N", "wall_time_s")}
                for r in line["cases"]], table_id="line-cases")
    page.section("Each bird", "birds")
    base, best = line["baseline"]["birds"], line["optimum_birds"]
    page.table([{"bird": b["bird"], "baseline hold (s)": b["hold_time_s"],
                 "baseline peak (N)": b["max_finger_force_N"], "baseline jam": b["jam"] or "none",
                 "answer hold (s)": o["hold_time_s"], "answer peak (N)": o["max_finger_force_N"],
                 "answer jam": o["jam"] or "none"} for b, o in zip(base, best)],
               caption=f"baseline {line['baseline']['line_rate_per_min']:.1f} birds/min; "
                       f"answer {result['line_rate_per_min']:.1f} birds/min (4x finer runs)",
               table_id="line-birds")
    page.section("The trade", "pareto")
    page.figure(pareto_figure(result), "line_pareto",
                "Worst bird's hold against the line rate over the searches' designs that no "
                "other beats in rate, hold and peak force at once (jams excluded)")
    grasp_figures(page, {"baseline": baseline, "answer (its worst-held bird)": optimum},
                  result["cap"]["N"])
    return page
