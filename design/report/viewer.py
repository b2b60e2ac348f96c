"""The interactive 3-D animation of grasp runs: a plotly figure with
animation frames, embedded whole in a report (plotly.js included, so the
page plays offline and makes no network request).

Each run has its own 3-D scene, side by side on one time axis: both drums,
every finger in its solved shape, the bird's ellipsoid, the belt with
stripes that travel with it, and each finger's force on the bird as an
arrow ending at the contact point, its length proportional to the force
and its colour the force against the cap. Above each scene: the time, the
belt's normal force N and the fingers touching the bird. Buttons play at
three speeds and pause; the slider scrubs.

Lengths in the figure are mm (to 0.1 mm), forces N.
"""

from __future__ import annotations

import numpy as np

from design.report.animation import (ARROW_MM_PER_N, BIRD_COLOUR, FORCE_SCALE, RunFrames,
                                     arrows, belt_half_width, bird_surface, both_drums,
                                     drum_surface, extent, stripes)
from design.report.grasp_figures import COLOURS, MM

#: playback speeds offered, as fractions of real time
SPEEDS = (0.1, 0.25, 1.0)
#: the box's longest side in plotly's aspect ratio units: the zoom of its
#: orthographic view, which scales with the aspect ratio
ZOOM = 2.4
#: height of a scene (px)
HEIGHT = 720


def _mm(a, digits: int = 1) -> list:
    """Coordinates (m) as mm rounded to ``digits`` decimals (whole mm as
    integers); nan as None (plotly's line breaks)."""
    mm = np.round(np.asarray(a, float).ravel() * MM, digits) + 0.0     # no -0.0
    gaps = np.isnan(mm)
    if not gaps.any():
        return (mm.astype(int) if digits == 0 else mm).tolist()
    return [None if gap else v for gap, v in zip(gaps, mm.tolist())]


def _polylines(curves: list[np.ndarray]) -> tuple[list, list, list]:
    """Curves (3, n) joined into one line trace's x, y, z (mm), broken by None."""
    gap = np.full((3, 1), np.nan)
    joined = np.hstack([np.hstack([c, gap]) for c in curves]) if curves else np.zeros((3, 0))
    return _mm(joined[0]), _mm(joined[1]), _mm(joined[2])


def _surface(points: np.ndarray, colour: str, scene: str, opacity: float = 1.0,
             name: str = "") -> dict:
    """A surface of one colour through a grid of points (3, n, m), to 1 mm."""
    return {"type": "surface", "scene": scene, "x": [_mm(r, 0) for r in points[0]],
            "y": [_mm(r, 0) for r in points[1]], "z": [_mm(r, 0) for r in points[2]],
            "colorscale": [[0, colour], [1, colour]], "showscale": False, "opacity": opacity,
            "hoverinfo": "skip", "name": name}


def _dynamic(run: RunFrames, k: int, scene: str, cmax: float,
             x_range: tuple[float, float]) -> list[dict]:
    """The traces of run's frame k (its last, for a run that ended sooner)
    that change in time: stripes, bird, fingers (one trace per finger of
    the right drum, with its mirror image on the left; colours as in the
    report's figures), arrow shafts and heads."""
    frame = run.frames[min(k, len(run.frames) - 1)]
    traces = []
    sx, sy, sz = _polylines(stripes(run, frame.belt_travel, x_range))
    traces.append({"type": "scatter3d", "scene": scene, "mode": "lines", "x": sx, "y": sy,
                   "z": sz, "line": {"color": "#9a9a9a", "width": 3}, "hoverinfo": "skip",
                   "showlegend": False})
    traces.append(_surface(bird_surface(run.setup, frame.y), BIRD_COLOUR, scene, name="bird"))
    for j, (name, curve) in enumerate(zip(run.names, frame.curves)):
        x, y, z = _polylines(both_drums([curve]))
        traces.append({"type": "scatter3d", "scene": scene, "mode": "lines", "x": x, "y": y,
                       "z": z, "name": f"finger {name}", "legendgroup": name,
                       "showlegend": scene == "scene", "hoverinfo": "name",
                       "line": {"color": COLOURS[j % len(COLOURS)], "width": 5}})
    drawn = arrows(frame)
    x, y, z = _polylines([np.column_stack([tail, tip]) for tail, tip, _, _ in drawn])
    colours = [v for *_, size in drawn for v in (size, size, size)]
    heads = {k: _mm([tip[i] for _, tip, _, _ in drawn]) for i, k in enumerate("xyz")}
    heads.update({k: [round(float(f[i]), 2) for _, _, f, _ in drawn]
                  for i, k in enumerate("uvw")})
    traces.append({"type": "scatter3d", "scene": scene, "mode": "lines", "x": x, "y": y, "z": z,
                   "name": "force on the bird", "showlegend": False, "hoverinfo": "skip",
                   "line": {"width": 9, "color": [round(c, 2) for c in colours] or [0.0],
                            "colorscale": FORCE_SCALE, "cmin": 0.0, "cmax": cmax}})
    traces.append({"type": "cone", "scene": scene, **heads, "anchor": "tip",
                   "sizemode": "raw", "sizeref": 0.2 * ARROW_MM_PER_N, "cmin": 0.0,
                   "cmax": cmax, "colorscale": FORCE_SCALE, "showscale": False,
                   "hoverinfo": "skip", "name": "force"})
    return traces


def _static(run: RunFrames, scene: str, x_range: tuple[float, float], cmax: float,
            cap: float | None) -> list[dict]:
    """Drums and belt: the traces that stay; in the first scene, the force
    colours' scale (on an invisible point: it stays when no finger touches)."""
    w = belt_half_width(run.setup)
    belt = np.array([[[x_range[0], x_range[1]]] * 2, [[-w, -w], [w, w]], [[0.0, 0.0]] * 2])
    traces = [_surface(drum_surface(run.setup, side), "#7f8c99", scene, 0.3, "drum")
              for side in (1, -1)] + [_surface(belt, "#4a4a4a", scene, 0.55, "belt")]
    if scene == "scene":
        title = "force on<br>the bird (N)" + ("<br>(top: the cap)" if cap is not None else "")
        traces.append({"type": "scatter3d", "scene": scene, "mode": "markers", "x": [0.0],
                       "y": [0.0], "z": [0.0], "hoverinfo": "skip", "showlegend": False,
                       "marker": {"size": 1, "opacity": 0, "color": [0.0], "cmin": 0.0,
                                  "cmax": cmax, "colorscale": FORCE_SCALE, "showscale": True,
                                  "colorbar": {"title": {"text": title}, "len": 0.45,
                                               "x": 1.0, "y": 0.55, "yanchor": "bottom"}}})
    return traces


def _caption(run: RunFrames, k: int) -> str:
    frame = run.frames[min(k, len(run.frames) - 1)]
    touching = ", ".join(frame.touching(run.names)) or "none"
    return (f"<b>{run.label}</b>  t = {frame.t:.3f} s   N = {frame.normal:.2f} N"
            f"<br>touching the bird: {touching}")


def animation_figure(runs: list[RunFrames], step: float, cap: float | None) -> dict:
    """The plotly figure (a dict) of ``runs`` side by side, frames every
    ``step`` s; the force colours run from 0 to ``cap`` (N), or to the
    largest force drawn when there is no cap."""
    peak = max((np.linalg.norm(f.forces, axis=1).max() for r in runs for f in r.frames),
               default=0.0)
    cmax = cap if cap is not None else max(peak, 1.0)
    box = extent(runs)
    x_range = (box[0, 0], box[0, 1])
    scenes = [f"scene{i + 1}" if i else "scene" for i in range(len(runs))]
    data, dynamic = [], []
    for run, scene in zip(runs, scenes):
        data += _static(run, scene, x_range, cmax, cap)
        first = len(data)
        data += _dynamic(run, 0, scene, cmax, x_range)
        dynamic += list(range(first, len(data)))
    longest = max(runs, key=lambda r: len(r.frames))
    frames = [{"name": str(k), "traces": dynamic,
               "data": [_changing(t) for run, scene in zip(runs, scenes)
                        for t in _dynamic(run, k, scene, cmax, x_range)],
               "layout": {"annotations": _annotations(runs, k)}}
              for k in range(len(longest.frames))]
    layout = {"height": HEIGHT, "margin": {"l": 0, "r": 0, "t": 60, "b": 0},
              "legend": {"x": 1.0, "xanchor": "left", "y": 0.5, "yanchor": "top",
                         "font": {"size": 11}},
              "annotations": _annotations(runs, 0),
              "updatemenus": [_buttons(step)], "sliders": [_slider(longest)]}
    width = 1.0 / len(runs)
    for i, scene in enumerate(scenes):
        layout[scene] = _scene(box, (i * width, (i + 1) * width))
    return {"data": data, "layout": layout, "frames": frames}


def _changing(trace: dict) -> dict:
    """What a frame changes of a trace: its coordinates, vectors and colours
    (plotly keeps the rest)."""
    out = {k: trace[k] for k in ("type", "x", "y", "z", "u", "v", "w") if k in trace}
    if isinstance(trace.get("line", {}).get("color"), list):
        out["line"] = {"color": trace["line"]["color"]}
    return out


def _annotations(runs: list[RunFrames], k: int) -> list[dict]:
    width = 1.0 / len(runs)
    return [{"text": _caption(run, k), "x": (i + 0.5) * width, "y": 1.0, "xref": "paper",
             "yref": "paper", "yanchor": "bottom", "showarrow": False, "align": "center",
             "font": {"size": 13}} for i, run in enumerate(runs)]


def _scene(box: np.ndarray, domain: tuple[float, float]) -> dict:
    axis = {name: {"range": [round(box[i, 0] * MM), round(box[i, 1] * MM)],
                   "title": {"text": f"{'XYZ'[i]} (mm)"}, "autorange": False}
            for i, name in enumerate(("xaxis", "yaxis", "zaxis"))}
    size = box[:, 1] - box[:, 0]
    ratio = dict(zip("xyz", (ZOOM * size / size.max()).round(3).tolist()))
    return {**axis, "aspectmode": "manual", "aspectratio": ratio,
            "domain": {"x": list(domain), "y": [0.0, 1.0]},
            "camera": {"eye": {"x": 0.9, "y": -0.5, "z": 0.5}, "up": {"x": 0, "y": 0, "z": 1},
                       "center": {"x": 0, "y": 0, "z": -0.1},
                       "projection": {"type": "orthographic"}}}


def _buttons(step: float) -> dict:
    """Play at each of SPEEDS, and pause."""
    play = [{"label": f"▶ {s:g}×", "method": "animate",
             "args": [None, {"frame": {"duration": 1000 * step / s, "redraw": True},
                             "transition": {"duration": 0}, "fromcurrent": True,
                             "mode": "immediate"}]} for s in SPEEDS]
    pause = {"label": "❚❚ pause", "method": "animate",
             "args": [[None], {"frame": {"duration": 0, "redraw": True},
                               "transition": {"duration": 0}, "mode": "immediate"}]}
    return {"type": "buttons", "direction": "left", "x": 0.0, "y": 0.0, "xanchor": "left",
            "yanchor": "top", "pad": {"t": 45}, "showactive": False, "buttons": play + [pause]}


def _slider(run: RunFrames) -> dict:
    """One step per frame of ``run`` (the longest), labelled with its time."""
    steps = [{"label": f"{f.t:.3f}", "method": "animate",
              "args": [[str(k)], {"frame": {"duration": 0, "redraw": True},
                                  "transition": {"duration": 0}, "mode": "immediate"}]}
             for k, f in enumerate(run.frames)]
    return {"active": 0, "steps": steps, "x": 0.3, "len": 0.7, "y": 0.0, "yanchor": "top",
            "pad": {"t": 30}, "currentvalue": {"prefix": "t = ", "suffix": " s",
                                               "font": {"color": "#222"}},
            "tickcolor": "rgba(0,0,0,0)", "font": {"color": "rgba(0,0,0,0)"}}


def animation_html(runs: list[RunFrames], step: float, cap: float | None,
                   div_id: str = "animation-view") -> str:
    """The figure as an HTML fragment with plotly.js inlined (no network)."""
    import plotly.io as pio

    return pio.to_html(animation_figure(runs, step, cap), include_plotlyjs=True,
                       full_html=False, auto_play=False, validate=False, div_id=div_id,
                       config={"displaylogo": False, "responsive": True})
