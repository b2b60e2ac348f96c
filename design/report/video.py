"""The animation of grasp runs as a video (MP4 with ffmpeg, else GIF),
drawn frame by frame with matplotlib's 3-D axes: the same frames and
objects as the report's interactive view (design/report/viewer.py), seen
from the same direction, one panel per run.

Lengths in mm, forces N; the video plays at ``speed`` times real time.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib import animation
from matplotlib.cm import ScalarMappable
from matplotlib.colors import LinearSegmentedColormap, Normalize
from matplotlib.figure import Figure

from design.report.animation import (BIRD_COLOUR, FORCE_SCALE, RunFrames, arrows,
                                     belt_half_width, bird_surface, both_drums, drum_surface,
                                     extent, stripes)
from design.report.grasp_figures import COLOURS, MM

#: the view's elevation and azimuth (degrees): the interactive view's camera
ELEVATION, AZIMUTH = 26.0, -29.0
FORCE_COLOURS = LinearSegmentedColormap.from_list("force", [(p, c) for p, c in FORCE_SCALE])


def ffmpeg_available() -> bool:
    """Whether matplotlib finds ffmpeg to write MP4."""
    return animation.writers.is_available("ffmpeg")


def write_video(runs: list[RunFrames], step: float, cap: float | None, path: Path,
                speed: float = 0.25) -> None:
    """Write the frames of ``runs`` side by side to ``path`` (.mp4 through
    ffmpeg, .gif through Pillow), ``step`` s apart, played at ``speed``
    times real time; forces coloured from 0 to ``cap`` (N; None: to the
    largest force drawn)."""
    peak = max(float(np.linalg.norm(f.forces, axis=1).max()) for r in runs for f in r.frames)
    norm = Normalize(0.0, cap if cap is not None else max(peak, 1.0))
    box = extent(runs) * MM
    fig = Figure(figsize=(6.4 * len(runs) + 1.2, 5.4), dpi=100)
    fig.subplots_adjust(left=0.02, right=0.86, bottom=0.02, top=0.92, wspace=0.12)
    axes = [fig.add_subplot(1, len(runs), i + 1, projection="3d") for i in range(len(runs))]
    fig.colorbar(ScalarMappable(norm=norm, cmap=FORCE_COLOURS),
                 cax=fig.add_axes((0.93, 0.25, 0.015, 0.5)),
                 label="force on the bird (N)" + (" (top: the cap)" if cap is not None else ""))

    def draw(k: int):
        for ax, run in zip(axes, runs):
            _draw(ax, run, min(k, len(run.frames) - 1), box, norm)
        return []

    count = max(len(r.frames) for r in runs)
    movie = animation.FuncAnimation(fig, draw, frames=count, blit=False)
    fps = speed / step
    writer = animation.FFMpegWriter(fps=fps) if path.suffix == ".mp4" else \
        animation.PillowWriter(fps=fps)
    movie.save(str(path), writer=writer)


def _draw(ax, run: RunFrames, k: int, box: np.ndarray, norm: Normalize) -> None:
    """One run's frame k on its 3-D axes (mm)."""
    frame = run.frames[k]
    ax.cla()
    for side in (1, -1):
        ax.plot_surface(*drum_surface(run.setup, side) * MM, color="#7f8c99", alpha=0.3,
                        linewidth=0)
    w = belt_half_width(run.setup) * MM
    xs = box[0]
    ax.plot_surface(np.array([xs, xs]), np.array([[-w, -w], [w, w]]), np.zeros((2, 2)),
                    color="#4a4a4a", alpha=0.5, linewidth=0)
    for s in stripes(run, frame.belt_travel, box[0] / MM):
        ax.plot(*s * MM, color="#9a9a9a", lw=1)
    ax.plot_surface(*bird_surface(run.setup, frame.y) * MM, color=BIRD_COLOUR, linewidth=0,
                    shade=True)
    for j, curve in enumerate(frame.curves):
        for c in both_drums([curve]):
            ax.plot(*c * MM, color=COLOURS[j % len(COLOURS)], lw=2)
    for tail, tip, _, magnitude in arrows(frame):
        ax.quiver(*tail * MM, *(tip - tail) * MM, color=FORCE_COLOURS(norm(magnitude)),
                  linewidth=2.5, arrow_length_ratio=0.25)
    ax.set_xlim(*box[0])
    ax.set_ylim(*box[1])
    ax.set_zlim(*box[2])
    ax.set_box_aspect(box[:, 1] - box[:, 0], zoom=1.1)
    ax.set_proj_type("ortho")
    ax.view_init(ELEVATION, AZIMUTH)
    ax.set_xlabel("X (mm)")
    ax.set_ylabel("Y (mm)")
    ax.set_zlabel("Z (mm)")
    touching = ", ".join(frame.touching(run.names)) or "none"
    ax.set_title(f"{run.label}: t = {frame.t:.3f} s, N = {frame.normal:.2f} N\n"
                 f"touching the bird: {touching}", fontsize=10)
