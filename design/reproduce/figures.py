"""Figures of the reproduction report: ours against the thesis's numbers.

Each function returns a matplotlib Figure (not attached to pyplot). Plots
show lengths in mm, forces in N, angles in degrees and times in s, as the
thesis's figures do; the report's tables stay SI.
"""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

from design.physics.clearance import facing
from design.physics.contact import ContactSolution
from design.reproduce.contact import FEM_PASS, THESIS_PASS, pass_angle

MM = 1e3


def beam_figure(table_2_1: dict, table_2_3: dict) -> Figure:
    """Figures 2-2 and 2-8 redrawn: deflected shapes by method (solutions by name)."""
    fig = Figure(figsize=(11, 4.2))
    left, right = fig.subplots(1, 2)
    styles = {"frisch-fay": "-", "shooting": ":", "collocation": "--", "small-deflection": "-."}
    for name, style in styles.items():
        s = table_2_1[name]
        left.plot(s.x * MM, s.y * MM, style, lw=1.6, label=name)
    fdm = table_2_1["fdm"]
    left.plot(fdm.x[::20] * MM, fdm.y[::20] * MM, "<", ms=5, label="fdm")
    left.set_title("Table 2-1: uniform EI = 0.08 N m², 15 N at 101.6 mm")
    for name, style in [("collocation", "-"), ("uniform EI = 0.08", "--")]:
        s = table_2_3[name]
        right.plot(s.x * MM, s.y * MM, style, lw=1.6,
                   label="non-uniform soft finger" if name == "collocation" else name)
    right.set_title("Table 2-3: non-uniform finger, 15 N at 76.2 mm")
    for ax in (left, right):
        _drawn_to_scale(ax, "x_f (mm)", "y_f (mm)", 8)
    return fig


def effective_ei_figure(at: tuple, thesis: dict, ours: dict, spread: dict) -> Figure:
    """Table 5-2: effective EI against contact position, thesis points and ours
    with the band it spans over the load grid (dicts by finger, N m^2)."""
    fig = Figure(figsize=(7, 4.4))
    ax = fig.add_subplot(1, 1, 1)
    x = np.asarray(at) * MM
    for k, finger in enumerate(thesis):
        colour = f"C{k}"
        ax.plot(x, thesis[finger], "o", color=colour, label=f"thesis, {finger}")
        ax.plot(x, ours[finger], "-", color=colour, label=f"ours, {finger} (15 N, 90°)")
        ax.fill_between(x, ours[finger] - spread[finger], ours[finger] + spread[finger],
                        color=colour, alpha=0.15, label=f"ours over 5-25 N, 60-120°, {finger}")
    ax.set_xlabel("contact position x_f (mm)")
    ax.set_ylabel("effective EI (N m²)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    return fig


def pass_figure(fine: dict[str, dict[float, ContactSolution]]) -> Figure:
    """Figure 3-17 redrawn: contact force over the Table 3-5 pass, ours (each
    friction rule) against the thesis's analytic values and the FEM's."""
    fig = Figure(figsize=(8, 4.4))
    ax = fig.add_subplot(1, 1, 1)
    labels = {"push": "ours, thesis's friction convention",
              "auto": "ours, friction from the sliding velocity"}
    for name, sols in fine.items():
        phi = np.array(list(sols))
        ax.plot(180 - phi, [s.force for s in sols.values()], "-", label=labels[name])
    ax.plot([180 - p for p in THESIS_PASS], [v[2] for v in THESIS_PASS.values()], "ks",
            label="thesis, Table 3-5")
    ax.plot([180 - pass_angle(x) for x in FEM_PASS], list(FEM_PASS.values()), "r^",
            label="FEM, Table 3-6")
    ax.set_xlabel("180° - φ (deg)")
    ax.set_ylabel("contact force |F| (N)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    return fig


def _series(run, pick) -> np.ndarray:
    return np.array([pick(r) for r in run.trajectory.records])


def finger_force_x_figure(runs: dict, band: float, thesis_peak: float) -> Figure:
    """Figure 5-7 redrawn: each finger's force against the bird's X for the
    runs given (by label), the thesis's 'dense' band ±``band`` (m) shaded."""
    fig = Figure(figsize=(9, 4.6))
    ax = fig.add_subplot(1, 1, 1)
    for k, (label, run) in enumerate(runs.items()):
        x = _series(run, lambda r: r.y[0]) * MM
        force = _series(run, lambda r: [f.magnitude for f in r.fingers])
        for j, gf in enumerate(run.setup.grasper.fingers):
            if force[:, j].max() > 0:
                ax.plot(x, force[:, j], "-" if k == 0 else "--", color=f"C{j}",
                        label=f"{label}, finger {gf.name}")
    ax.axvspan(-band * MM, band * MM, color="0.5", alpha=0.12, label="thesis: forces dense here")
    ax.axhline(thesis_peak, color="k", ls=":", label=f"thesis peak ≈ {thesis_peak:g} N")
    ax.set_xlim(-250, 250)
    ax.set_xlabel("bird centre X (mm)")
    ax.set_ylabel("finger force on the bird (N)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, ncol=2)
    return fig


def path_figure(runs: dict, title: str, height: float | None = None) -> Figure:
    """Figures 5-17/5-19 redrawn: the centre's height Z against X for each run
    (by label), with the thesis's stated height (m) if given."""
    fig = Figure(figsize=(9, 4.2))
    ax = fig.add_subplot(1, 1, 1)
    for label, run in runs.items():
        ax.plot(_series(run, lambda r: r.y[0]) * MM, _series(run, lambda r: r.y[1]) * MM,
                label=label)
    if height is not None:
        ax.axhline(height * MM, color="k", ls=":", label=f"thesis: {height * MM:g} mm")
    ax.set_title(title)
    ax.set_xlabel("centre X (mm)")
    ax.set_ylabel("centre Z (mm)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    return fig


def transverse_figure(graspers: dict, birds: dict, families: tuple[str, ...] = ("1", "2")
                      ) -> Figure:
    """Figure 5-3 redrawn: the resting birds' transverse sections through the
    drum axes and the straight fingers of ``families`` facing them, one line
    style per grasper (dicts by label; the right drum, Y and Z in mm)."""
    fig = Figure(figsize=(7, 4.6))
    ax = fig.add_subplot(1, 1, 1)
    t = np.linspace(0.0, 2 * np.pi, 361)
    for k, (label, bird) in enumerate(birds.items()):
        ax.plot(bird.lam * np.cos(t) * MM, bird.gamma * (1 + np.sin(t)) * MM, color=f"C{k}",
                lw=1.8, label=f"{label} ({bird.lam * MM:.0f} x {bird.gamma * MM:.0f} mm)")
    for style, (label, grasper) in zip(("-", "--", ":"), graspers.items()):
        drum = grasper.drum(1.0)
        shown = [gf for gf in grasper.fingers
                 if gf.design_name in families and gf.name.endswith("a")]
        for k, gf in enumerate(shown):
            (y0, z0), (y1, z1) = facing(drum, gf.mount, gf.finger.length)
            ax.plot([y0 * MM, y1 * MM], [z0 * MM, z1 * MM], "k" + style, lw=1.4,
                    label=f"fingers {', '.join(families)}, {label}" if k == 0 else None)
    ax.axhline(0.0, color="0.5", lw=0.8)
    _drawn_to_scale(ax, "Y (mm, the right drum's side)", "Z above the belt (mm)", 7)
    return fig


def _drawn_to_scale(ax, xlabel: str, ylabel: str, legend_size: int) -> None:
    """Labels, equal scales on both axes (shapes and sections), grid, legend."""
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_aspect("equal")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=legend_size)
