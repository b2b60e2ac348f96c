"""Reports of beam and contact scenes, from their result dicts alone."""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure
from matplotlib.patches import Ellipse as EllipsePatch

from design.report.grasp import reproduce_section
from design.report.display import degrees
from design.report.page import Page

MM = 1e3
#: more cases than this are drawn as a sweep (tip against load), not shape by shape
MAX_SHAPES = 12


def _verdict(page: Page, cases: list[dict], what: str) -> None:
    failed = [i for i, c in enumerate(cases) if not c["converged"]]
    if failed:
        page.banner(f"{len(failed)} of {len(cases)} {what} did not converge (cases "
                    f"{', '.join(map(str, failed[:10]))}); see 'message' in result.json",
                    "failed")
    else:
        page.banner(f"All {len(cases)} {what} converged", "passed")


def beam_page(result: dict) -> Page:
    cases = result["cases"]
    page = Page(f"Beam: {result['name']}")
    _verdict(page, cases, "loads")
    page.section("Finger and loads", "scene")
    page.text(f"Finger {result['finger']}; method {result['method']}.")
    page.table([{"F (N)": c["F"], "α (°)": degrees(c["alpha"]), "at (m)": c["at"],
                 "tip x (m)": c["tip"]["x"], "tip y (m)": c["tip"]["y"],
                 "tip ψ (°)": degrees(c["tip"]["psi"]), "error estimate (m)": c["error_estimate"],
                 "branch": c["branch"], "converged": c["converged"]}
                for c in cases[:200]], "Loads and load-point results (angles in degrees, the rest SI; "
               "the first 200)",
               "cases-table", digits=6)
    page.section("Deflection", "deflection")
    fig = Figure(figsize=(12, 4.4))
    shape, moment = fig.subplots(1, 2)
    if len(cases) <= MAX_SHAPES:
        for c in cases:
            label = f"F = {c['F']:.3g} N"
            shape.plot(np.array(c["shape"]["x"]) * MM, np.array(c["shape"]["y"]) * MM,
                       label=label)
            moment.plot(np.array(c["shape"]["s"]) * MM, c["shape"]["M"], label=label)
        shape.set_aspect("equal", adjustable="datalim")
        shape.set_xlabel("x (mm)")
        shape.set_ylabel("y (mm)")
        moment.set_xlabel("arc length s (mm)")
        moment.set_ylabel("bending moment M (N m)")
        shape.legend(fontsize=8)
        caption = ("The deflected finger from its clamp to its free end (straight past the "
                   "load point) and its bending moment")
    else:
        force = [c["F"] for c in cases]
        shape.plot(force, [c["tip"]["y"] * MM for c in cases], ".")
        shape.set_xlabel("F (N)")
        shape.set_ylabel("load-point deflection y (mm)")
        moment.plot(force, [c["base_moment"] for c in cases], ".")
        moment.set_xlabel("F (N)")
        moment.set_ylabel("base moment (N m)")
        caption = "Load-point deflection and base moment over the sweep"
    for ax in (shape, moment):
        ax.grid(alpha=0.3)
    page.figure(fig, "deflection", caption)
    reproduce_section(page, result,
                      [{"setting": k, "value": str(v)} for k, v in result["solver"].items()],
                      result["solve_time_s"])
    return page


def contact_page(result: dict) -> Page:
    cases = result["cases"]
    page = Page(f"Contact: {result['name']}")
    _verdict(page, cases, "poses")
    page.section("Finger, object and poses", "scene")
    page.text(f"Finger {result['finger']}; drum radius {result['drum_radius']} m; object "
              f"semi-axes {result['object']['semi_axes']} m; friction {result['friction']}; "
              f"method {result['method']}.")
    page.table([{"finger angle (°)": degrees(c["finger_angle"]),
                 "object X (m)": c["object_center"][0],
                 "object Y (m)": c["object_center"][1], "contact": c["contact"],
                 "force (N)": c["force"],
                 "point x_f (m)": c["point"][0] if c["point"] else None,
                 "point y_f (m)": c["point"][1] if c["point"] else None,
                 "ψ0 (°)": degrees(c["psi"]), "friction": c["friction"],
                 "converged": c["converged"]}
                for c in cases], "Contact at every pose (finger frame; angles in degrees, the rest "
               "SI)", "cases-table")
    page.section("Contact force and finger shapes", "forces")
    fig = Figure(figsize=(12, 4.6))
    force, shapes = fig.subplots(1, 2)
    force.plot(np.degrees([c["finger_angle"] for c in cases]), [c["force"] for c in cases], "o-")
    force.set_xlabel("finger angle φ (°)")
    force.set_ylabel("contact force (N)")
    a, b = result["object"]["semi_axes"]
    step = max(1, len(cases) // MAX_SHAPES)
    for c in cases[::step]:
        line, = shapes.plot(np.array(c["shape"]["x"]) * MM, np.array(c["shape"]["y"]) * MM)
        x0, y0 = c["object_center"]
        shapes.add_patch(EllipsePatch((x0 * MM, y0 * MM), 2 * a * MM, 2 * b * MM,
                                      angle=np.degrees(result["object"]["orientation"]),
                                      fill=False, color=line.get_color(), ls="--"))
    shapes.set_aspect("equal", adjustable="datalim")
    shapes.set_xlabel("X (mm)")
    shapes.set_ylabel("Y (mm)")
    for ax in (force, shapes):
        ax.grid(alpha=0.3)
    page.figure(fig, "contact", "Contact force against finger angle; the finger and the object "
                "at a selection of poses (drum frame)")
    reproduce_section(page, result,
                      [{"setting": k, "value": str(v)} for k, v in result["solver"].items()],
                      result["solve_time_s"])
    return page
