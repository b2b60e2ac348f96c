"""The report of a grasp scene (``design simulate`` on ``kind: grasp``)."""

from __future__ import annotations

import numpy as np

from design.report import grasp_figures as gf
from design.report.display import degrees, shown
from design.report.page import Page
from design.report.animation import ARROW_MM_PER_N
from design.solvers.grasp.simulation import GraspRun


def summary_rows(run: GraspRun, label: str = "") -> list[dict]:
    """The run's headline numbers as table rows (quantity, value, unit)."""
    s = run.summary
    windows = ", ".join(f"{a:.3f}–{b:.3f}" for a, b in s["hold_windows"]) or "none"
    rows = [("longest N = 0 hold", s["hold_time_s"], "s"), ("N = 0 windows", windows, "s"),
            ("peak finger force", s["max_finger_force_N"], "N"),
            ("finger with the peak", s["max_finger_force_finger"], ""),
            ("time of the peak", s["max_finger_force_time_s"], "s"),
            ("centre rise (from its start)", s["centre_rise_m"], "m"),
            ("lowest point above the belt", s["belt_clearance_m"], "m"),
            ("least belt normal force", s["min_normal_force_N"], "N"),
            ("largest pitch", degrees(abs(s["max_pitch_rad"])), "deg")]
    if s["local_error_estimate"] is not None:
        rows.append(("largest estimated local error of a BDF-4 step (position)",
                     s["local_error_estimate"]["position_m"], "m"))
    return [{"quantity": q, **({"run": label} if label else {}), "value": v, "unit": u}
            for q, v, u in rows]


def animation_section(page: Page, result: dict) -> None:
    """The 3-D animation of the result's runs (its ``animation`` entry),
    the fingers solved again at every frame; where a contact cannot be
    solved, the reason instead."""
    from design.errors import ProblemFileError
    from design.report.animation import animated_runs
    from design.solvers.grasp.fingers import ContactFailed

    page.section("Animation", "animation")
    try:
        runs = animated_runs(result["animation"])
    except (ContactFailed, ProblemFileError) as exc:
        page.text(f"No animation: {exc}.")
        return
    animation_view(page, runs, result["animation"])


def animation_view(page: Page, runs: list, record: dict) -> None:
    """The interactive view of ``runs`` (RunFrames) and what it shows."""
    from design.report.viewer import animation_html

    step, cap = record["frame_step_s"], record["cap_N"]
    recorded = ", ".join(f"{r.label} {r.recorded}" for r in runs)
    page.text(f"Frames every {1e3 * step:g} ms ({len(runs[0].frames)} frames; the bird's state "
              f"interpolated linearly between the run's recorded instants: {recorded}); at "
              f"each frame every finger's contact is solved again at that state. Arrows: each "
              f"finger's force on the bird, {ARROW_MM_PER_N:g} mm per N, coloured "
              + (f"against the cap of {cap:.2f} N." if cap is not None else
                 "from no force to the largest drawn (no cap).")
              + " Drag to turn the view, scroll to zoom; a finger's legend entry hides it.")
    page.fragment(animation_html(runs, step, cap))


def grasp_figures(page: Page, runs: dict[str, GraspRun], cap: float | None = None) -> None:
    """The figure sections every grasp report has; the last run in ``runs``
    is the one drawn in detail."""
    run = list(runs.values())[-1]
    page.section("Finger layout on the drums", "layout")
    page.text("Fingers as mounted at t = 0 (straight, unloaded). The right drum's fingers "
              "are drawn in full colour, the left drum's mirror images paler.")
    page.figure(gf.layout_figure({k or 'design': r.setup for k, r in runs.items()}), "layout",
                "Finger layout: top, side and front views (mm)")
    page.section("The bird's path", "path")
    page.figure(gf.path_figure(run), "path",
                "Side view of the bird and the deflected fingers at key instants; centre "
                "rise and pitch against time (N = 0 windows shaded)")
    page.section("Belt normal force", "normal-force")
    page.figure(gf.normal_force_figure(runs), "normal_force",
                "Belt normal force N(t); the N = 0 windows of the last run shaded")
    page.section("Finger forces", "finger-forces")
    page.figure(gf.finger_force_figure(run, cap), "finger_forces",
                "Every finger's contact force against time and against the bird's position"
                + (" with the bruise cap" if cap is not None else ""))
    page.section("Contact loci on the bird", "contact-loci")
    page.figure(gf.contact_loci_figure(run), "contact_loci",
                "Where the fingers pressed on the bird's surface (body frame), coloured by "
                "force: dots the right drum, crosses the left")


def grasp_page(result: dict, run: GraspRun) -> Page:
    page = Page(f"Grasp simulation: {result['name']}")
    s = result["summary"]
    if s["ok"]:
        page.banner(f"Simulated {result['duration']:.3g} s: longest N = 0 hold "
                    f"{s['hold_time_s']:.4f} s, peak finger force {s['max_finger_force_N']:.2f} N "
                    f"(finger {s['max_finger_force_finger']})", "passed")
    else:
        page.banner(f"The integration stopped early: {s['message']}", "failed")
    page.section("Scene", "scene")
    b = result["bird"]
    page.text(f"Bird {b.get('name', '')}: semi-axes {np.round(np.array(b['semi_axes']), 4)} m, "
              f"mass {b.get('mass')} kg, starting at X = {result['start_X']:.3f} m on the belt; "
              f"drums at {result['drum_speed'] * shown('rad/s')[1]:.2f} rpm, "
              f"{result['grasper']['spacing']:.3f} m "
              f"apart; finger friction {result['friction']['finger']}, belt friction "
              f"{result['friction']['conveyor']}.")
    page.table([{**{k: f[k] for k in ("name", "group", "length", "height", "drum_radius")},
                 **{k: degrees(f[k]) for k in ("angle", "phi_x", "phi_y")}}
                for f in result["grasper"]["fingers"]], "Fingers of the right drum (lengths in m, "
               "angles in degrees)")
    page.section("Summary", "summary")
    page.table(summary_rows(run), "Run summary (units as given)", "summary-table")
    animation_section(page, result)
    grasp_figures(page, {"": run})
    reproduce_section(page, result,
                      [{"setting": k, "value": v} for k, v in result["solver"].items()],
                      result["stats"]["wall_time_s"])
    return page


def reproduce_section(page: Page, result: dict, settings: list[dict], wall_time: float) -> None:
    """The report's last section: version, wall time (s), the command that
    reruns the run (its scene file as it was named) and the solver settings."""
    verb = "solve" if result["kind"] == "design" else "simulate"
    scene = result.get("scene_file")
    command = (f"Command: design {verb} {scene}" if scene else
               "The scene was given as content from Python, not as a file.")
    page.section("Reproduce this run", "reproduce")
    page.text(f"Toolkit version {result['toolkit_version']}; wall time {wall_time:.1f} s. "
              f"{command}")
    page.table(settings, "Solver settings", "settings-table")
