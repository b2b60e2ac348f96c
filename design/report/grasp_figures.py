"""Figures of a grasp run: layout, path, belt force, finger forces, contact loci.

Conventions: world X along the belt, Y across it (the right drum at
Y = -spacing/2), Z up; the bird's body frame x (length), y (width), z
(height). Lengths in the figures are mm, forces N, times s. Only the right
drum's fingers are listed; the left drum mirrors them (Y → -Y).
"""

from __future__ import annotations

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.patches import Polygon
from matplotlib.patches import Ellipse as EllipsePatch

from design.physics.contact import ContactSolution
from design.solvers.contact.spatial import SpatialSolution
from design.solvers.grasp.simulation import GraspRun, GraspSetup

MM = 1e3
#: height (mm of the side view) kept above the birds for each key instant's label
LABEL_MM = 25.0
#: one colour per finger, in grasper order
COLOURS = ["#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2",
           "#7f7f7f", "#bcbd22", "#17becf"]


def finger_curves(setup: GraspSetup, t: float, states=None) -> list[np.ndarray]:
    """World points (3, n) of every right-drum finger at time t: the deflected
    shape where a contact solution is given (planar: in the finger's bending
    plane; spatial: the rod's points in the finger frame), else the straight
    finger."""
    drum = setup.grasper.drum(setup.drum_speed)
    curves = []
    for i, gf in enumerate(setup.grasper.fingers):
        base, R = drum.frame(gf.mount, t)
        sol = None if states is None else states[i].solution
        curves.append(base[:, None] + R @ _finger_points(sol, gf.finger.length))
    return curves


def _finger_points(sol, length: float) -> np.ndarray:
    """The finger's points (3, n) in its frame (m): a contact solution's shape,
    else the straight finger."""
    if isinstance(sol, SpatialSolution) and sol.contact and sol.shape_points is not None:
        return sol.shape_points
    if isinstance(sol, ContactSolution) and sol.contact:
        return np.vstack([sol.shape_x, sol.shape_y, np.zeros(len(sol.shape_x))])
    return np.vstack([np.linspace(0.0, length, 2), np.zeros((2, 2))])


def drum_profile(setup: GraspSetup) -> list[tuple[float, float]]:
    """The right drum's outline as (height m, radius m) pairs, bottom to top:
    the radius at each height a finger is mounted (the largest where
    several are); one height gives a disc 10 mm thick."""
    rings: dict[float, float] = {}
    for gf in setup.grasper.fingers:
        h = gf.mount.height
        rings[h] = max(rings.get(h, 0.0), gf.mount.radius)
    profile = sorted(rings.items())
    if len(profile) == 1:
        (h, r), = profile
        profile = [(h - 0.005, r), (h + 0.005, r)]
    return profile


def _bird_outline(setup: GraspSetup, y: np.ndarray, plane: str) -> EllipsePatch:
    """The bird's outline (mm) in the side (X-Z) or front (Y-Z) view."""
    b = setup.bird
    if plane == "side":
        return EllipsePatch((y[0] * MM, y[1] * MM), 2 * b.eta * MM, 2 * b.gamma * MM,
                            angle=-np.degrees(y[2]), fill=False, color="k", lw=1.2)
    return EllipsePatch((0.0, y[1] * MM), 2 * b.lam * MM, 2 * b.gamma * MM, fill=False,
                        color="k", lw=1.2)


def split_at_belt(curve: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A finger's points (3, n) as its part above the belt (Z ≥ 0) and its
    part below, each (3, m) with nan where the other part is (a line
    break), and the points (3, k) where it crosses the belt."""
    z = curve[2]
    points, crossings = [curve[:, :1]], []
    for i in range(curve.shape[1] - 1):
        if (z[i] < 0.0) != (z[i + 1] < 0.0):
            s = z[i] / (z[i] - z[i + 1])
            cross = curve[:, i] + s * (curve[:, i + 1] - curve[:, i])
            points.append(cross[:, None])
            crossings.append(cross)
        points.append(curve[:, i + 1:i + 2])
    full = np.hstack(points)
    above, below = full.copy(), full.copy()
    above[:, full[2] < -1e-12] = np.nan
    below[:, full[2] > 1e-12] = np.nan
    return above, below, np.array(crossings).T.reshape(3, -1)


def _draw_fingers(ax, curves, axes: tuple[int, int], style: str = "-", alpha: float = 1.0,
                  label_prefix: str = "", names=None) -> None:
    """Right-drum fingers and their left mirror images projected on two world
    axes; where Z is drawn, a finger's part below the belt dotted and its
    crossing of the belt marked x."""
    below_label = "finger meets the belt (below it: dotted)"
    for i, c in enumerate(curves):
        colour = COLOURS[i % len(COLOURS)]
        label = f"{label_prefix}finger {names[i]}" if names else None
        mirrors = [c] + ([c * np.array([[1.0], [-1.0], [1.0]])] if 1 in axes else [])
        for k, m in enumerate(mirrors):     # the mirror image is distinct only where Y is drawn
            shade = alpha * (0.5 if k else 1.0)
            if 2 not in axes:
                ax.plot(m[axes[0]] * MM, m[axes[1]] * MM, style, color=colour, alpha=shade,
                        lw=2, label=None if k else label)
                continue
            above, below, crossings = split_at_belt(m)
            ax.plot(above[axes[0]] * MM, above[axes[1]] * MM, style, color=colour, alpha=shade,
                    lw=2, label=None if k else label)
            if crossings.size:
                ax.plot(below[axes[0]] * MM, below[axes[1]] * MM, ":", color=colour,
                        alpha=shade, lw=1.5)
                listed = below_label in ax.get_legend_handles_labels()[1]
                ax.plot(crossings[axes[0]] * MM, crossings[axes[1]] * MM, "x", color="k",
                        ms=6, label=None if listed else below_label)


def layout_figure(setups: dict[str, GraspSetup], t: float = 0.0) -> Figure:
    """The fingers as mounted (straight, unloaded) at time t, in top (X-Y),
    side (X-Z) and front (Y-Z) views; one line style per design."""
    fig = Figure(figsize=(13, 5.2), layout="constrained")
    axes = fig.subplots(1, 3)
    styles = ["-", "--", ":"]
    for k, (label, setup) in enumerate(setups.items()):
        g = setup.grasper
        names = [f.name for f in g.fingers] if k == 0 else None
        curves = finger_curves(setup, t)
        for ax, pair in zip(axes, [(0, 1), (0, 2), (1, 2)]):
            _draw_fingers(ax, curves, pair, styles[k % 3], 1.0 if k == 0 else 0.8,
                          "", names if ax is axes[0] else None)
        outline = dict(fill=False, ls=styles[k % 3], color="0.4")
        for view, ax in zip(("top", "side", "front"), axes):
            for points in drum_outlines(setup, view):
                ax.add_patch(Polygon((points * MM).T, closed=True, **outline))
        axes[0].plot([], [], styles[k % 3], color="0.2", label=label)
    for ax, (xl, yl), title in zip(axes, [("X", "Y"), ("X", "Z"), ("Y", "Z")],
                                   ["top view", "side view", "front view"]):
        ax.set_xlabel(f"{xl} (mm)")
        ax.set_ylabel(f"{yl} (mm)")
        ax.set_title(f"{title}, t = {t:.2f} s")
        ax.set_aspect("equal", adjustable="datalim")
        ax.grid(alpha=0.3)
    entries = {lab: h for ax in axes for h, lab in zip(*ax.get_legend_handles_labels())}
    fig.legend(list(entries.values()), list(entries), loc="outside lower center", ncol=9,
               fontsize=7)
    return fig


def drum_outlines(setup: GraspSetup, view: str) -> list[np.ndarray]:
    """Both drums' outlines (2, n) in m, as seen in the ``top`` (X-Y), ``side``
    (X-Z) or ``front`` (Y-Z) view: the largest ring from above, the profile
    through the rings (:func:`drum_profile`) from the side (tilted with the
    axis) and the front; the drums coincide in the side view."""
    g = setup.grasper
    profile = drum_profile(setup)
    if view == "top":
        a = np.linspace(0.0, 2 * np.pi, 73)
        r = max(radius for _, radius in profile)
        return [np.vstack([g.x + r * np.cos(a), side * g.spacing / 2 + r * np.sin(a)])
                for side in (-1, 1)]
    h = np.array([p[0] for p in profile] + [p[0] for p in reversed(profile)])
    r = np.array([p[1] for p in profile] + [-p[1] for p in reversed(profile)])
    if view == "side":
        c, s = np.cos(g.tilt), np.sin(g.tilt)
        return [np.vstack([g.x + c * r + s * h, -s * r + c * h])]
    return [np.vstack([side * g.spacing / 2 + r, h]) for side in (-1, 1)]


def key_instants(run: GraspRun) -> list[tuple[float, str]]:
    """First finger contact, start and end of the longest hold, peak force."""
    s = run.summary
    recs = run.trajectory.records
    out = []
    touching = [r.t for r in recs if any(f.magnitude > 0 for f in r.fingers)]
    if touching:
        out.append((touching[0], "first contact"))
    windows = s["hold_windows"]
    if windows:
        a, b = max(windows, key=lambda w: w[1] - w[0])
        out += [(a, "hold starts"), (b, "hold ends")]
    out.append((s["max_finger_force_time_s"], "peak force"))
    return sorted(out)


def _record_at(run: GraspRun, t: float):
    recs = run.trajectory.records
    return recs[int(np.argmin([abs(r.t - t) for r in recs]))]


def _instants_drawn(run: GraspRun) -> list:
    """The records at the key instants, those at one record merged: (record,
    the instants' names)."""
    drawn: dict[int, tuple] = {}
    for tk, name in key_instants(run):
        r = _record_at(run, tk)
        drawn.setdefault(id(r), (r, []))[1].append(name)
    return list(drawn.values())


def _stack(ax, labels: list) -> None:
    """Raise each label (an annotation placed in offset points) above the
    ones before it that it would overlap, once the figure is laid out (the
    labels take no part in the layout)."""
    for label in labels:
        label.set_in_layout(False)
    renderer = FigureCanvasAgg(ax.figure).get_renderer()
    ax.figure.draw_without_rendering()
    placed = []
    for label in labels:
        box = label.get_window_extent(renderer)
        while (hit := next((b for b in placed if box.overlaps(b)), None)) is not None:
            dx, dy = label.xyann
            label.xyann = (dx, dy + (hit.y1 - box.y0 + 2) * 72 / ax.figure.dpi)
            box = label.get_window_extent(renderer)
        placed.append(box)


def path_figure(run: GraspRun) -> Figure:
    """Side view of the bird's path with the bird and the deflected fingers
    at the key instants; its height and pitch against time."""
    setup = run.setup
    recs = run.trajectory.records
    t = np.array([r.t for r in recs])
    y = np.array([r.y for r in recs])
    fig = Figure(figsize=(13, 8))
    top = fig.add_subplot(2, 1, 1)
    top.plot(y[:, 0] * MM, y[:, 1] * MM, "k-", lw=1, label="bird centre")
    labels = []
    for k, (r, names) in enumerate(_instants_drawn(run)):
        top.add_patch(_bird_outline(setup, r.y, "side"))
        _draw_fingers(top, finger_curves(setup, r.t, r.fingers), (0, 2), alpha=0.9,
                      names=[f.name for f in setup.grasper.fingers] if k == 0 else None)
        labels.append(top.annotate(f"{', '.join(names)}\nt = {r.t:.3f} s",
                                   (r.y[0] * MM, (r.y[1] + setup.bird.gamma) * MM),
                                   xytext=(0, 4), textcoords="offset points", ha="center",
                                   va="bottom", fontsize=8))
    top.axhline(0.0, color="0.3", lw=3, label="belt")
    top.set_aspect("equal", adjustable="datalim")
    top.set_xlabel("X (mm)")
    top.set_ylabel("Z (mm)")
    top.set_title("side view: the bird and the right drum's fingers at key instants")
    top.legend(fontsize=7, ncol=2, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    # room above the birds for the labels, stacked
    top.update_datalim([(MM * y[0, 0], MM * (y[:, 1].max() + setup.bird.eta)
                         + LABEL_MM * len(labels))])
    top.autoscale_view()
    _stack(top, labels)
    ax1 = fig.add_subplot(2, 2, 3)
    ax1.plot(t, (y[:, 1] - y[0, 1]) * MM)
    ax1.set_xlabel("t (s)")
    ax1.set_ylabel("centre rise Z - Z0 (mm)")
    ax2 = fig.add_subplot(2, 2, 4)
    ax2.plot(t, np.degrees(y[:, 2]))
    ax2.set_xlabel("t (s)")
    ax2.set_ylabel("pitch θ (°)")
    for ax in (ax1, ax2):
        ax.grid(alpha=0.3)
        _shade(ax, run.summary["hold_windows"])
    return fig


def _shade(ax, windows) -> None:
    for k, (a, b) in enumerate(windows):
        ax.axvspan(a, b, color="tab:green", alpha=0.15, label="N = 0" if k == 0 else None)


def normal_force_figure(runs: dict[str, GraspRun]) -> Figure:
    """The belt's normal force N(t) with the N = 0 windows shaded, and the
    belt speed."""
    fig = Figure(figsize=(11, 4.2))
    ax = fig.add_subplot(1, 1, 1)
    speed = ax.twinx()
    for k, (label, run) in enumerate(runs.items()):
        recs = run.trajectory.records
        t = [r.t for r in recs]
        ax.plot(t, [r.normal for r in recs], "-" if k == 0 else "--", label=f"N, {label}")
        speed.plot(t, [r.belt_speed for r in recs], ":", color="0.4" if k == 0 else "0.7",
                   label=f"belt speed, {label}")
    _shade(ax, list(runs.values())[-1].summary["hold_windows"])
    ax.set_xlabel("t (s)")
    ax.set_ylabel("belt normal force N (N)")
    speed.set_ylabel("belt speed (m/s)")
    ax.grid(alpha=0.3)
    lines = ax.get_legend_handles_labels()
    more = speed.get_legend_handles_labels()
    ax.legend(lines[0] + more[0], lines[1] + more[1], fontsize=8, loc="upper right")
    return fig


def finger_force_figure(run: GraspRun, cap: float | None = None) -> Figure:
    """Every finger's contact force against time and against the bird's X,
    with the cap."""
    recs = run.trajectory.records
    t = np.array([r.t for r in recs])
    x = np.array([r.y[0] for r in recs])
    force = np.array([[f.magnitude for f in r.fingers] for r in recs])
    names = [f.name for f in run.setup.grasper.fingers]
    fig = Figure(figsize=(13, 4.4))
    axes = fig.subplots(1, 2)
    for j, name in enumerate(names):
        if force[:, j].max() <= 0:
            continue
        for ax, abscissa in zip(axes, (t, x * MM)):
            ax.plot(abscissa, force[:, j], color=COLOURS[j % len(COLOURS)], label=f"finger {name}")
    for ax, label in zip(axes, ("t (s)", "bird centre X (mm)")):
        if cap is not None:
            ax.axhline(cap, color="r", ls="--", label=f"cap {cap:.1f} N")
        ax.set_xlabel(label)
        ax.set_ylabel("contact force on the bird (N)")
        ax.grid(alpha=0.3)
    _shade(axes[0], run.summary["hold_windows"])
    if axes[0].get_legend_handles_labels()[0]:        # nothing to list when nothing touched
        axes[0].legend(fontsize=8)
    return fig


def contact_loci_figure(run: GraspRun) -> Figure:
    """Where each finger touched the bird, on its surface (body frame), in
    side (x-z) and top (x-y) projections, coloured by force: where bruises
    would be."""
    b = run.setup.bird
    fig = Figure(figsize=(13, 4.6))
    axes = fig.subplots(1, 2)
    for ax, (i, j), (w, h), title in zip(axes, [(0, 2), (0, 1)],
                                         [(b.eta, b.gamma), (b.eta, b.lam)],
                                         ["side (body x-z)", "top (body x-y)"]):
        ax.add_patch(EllipsePatch((0, 0), 2 * w * MM, 2 * h * MM, fill=False, color="k"))
        ax.set_title(title)
        ax.set_xlabel(f"body {'xyz'[i]} (mm)")
        ax.set_ylabel(f"body {'xyz'[j]} (mm)")
        ax.set_aspect("equal")
        ax.grid(alpha=0.3)
    points, forces, fingers = [], [], []
    for r in run.trajectory.records:
        for k, f in enumerate(r.fingers):
            if f.body_point is not None and f.magnitude > 0:
                points.append(f.body_point)
                forces.append(f.magnitude)
                fingers.append(k)
    if points:
        p = np.array(points) * MM
        vmax = max(forces)
        for ax, (i, j) in zip(axes, [(0, 2), (0, 1)]):
            sc = ax.scatter(p[:, i], p[:, j], c=forces, s=8, cmap="inferno_r", vmin=0,
                            vmax=vmax)
            if j == 1:          # the left drum's contacts mirror the right's across y
                ax.scatter(p[:, i], -p[:, j], c=forces, s=8, cmap="inferno_r", vmin=0,
                           vmax=vmax, marker="x")
        fig.colorbar(sc, ax=axes, label="contact force (N)")
    return fig

