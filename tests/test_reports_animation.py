"""The 3-D animation of grasp runs: the frame states a result keeps, the
fingers solved again there, ``design animate``, the report's size, and the
static figures' labels and belt crossings."""

from __future__ import annotations

import json
from itertools import combinations
from pathlib import Path

import numpy as np
import pytest

from design.cli import main
from design.io.grasp_scene import GraspSettings
from design.io.scene_writer import grasp_spec
from design.report import grasp_figures as gf
from design.report.animation import animated_runs, solve_frames
from design.report.video import write_video
from design.report.viewer import animation_html
from design.run.animation import MAX_FRAMES, STATE, animation_record, frame_states, frame_step
from design.run.grasp import timeseries
from tests.design_cases import LOOP, shared_simulate_grasp, sharing_simulations, short_setup
from tests.test_reports import short_scene

PROBLEMS = Path(__file__).parent.parent / "problems"
#: the report's budget for a 2 s run, bytes
REPORT_BUDGET = 8e6


@pytest.fixture(scope="module")
def short_run():
    """The short grasp, the design tests' shared baseline run."""
    return shared_simulate_grasp(short_setup(), LOOP.simulator)


@pytest.fixture(scope="module")
def grasp_out(tmp_path_factory):
    """``design simulate`` of the short grasp (its shared run) and its folder."""
    tmp = tmp_path_factory.mktemp("grasp")
    with sharing_simulations():
        assert main(["simulate", str(short_scene(tmp)), "--out", str(tmp / "out"),
                     "--quiet"]) == 0
    return tmp / "out"


def test_frame_step_keeps_a_run_within_the_frame_budget():
    assert frame_step(1.0) == 0.02 and frame_step(2.0) == 0.025
    for duration in (0.3, 0.85, 1.0, 1.6, 2.0, 5.0, 30.0):
        assert int(duration / frame_step(duration)) + 1 <= MAX_FRAMES


def test_frame_states_interpolate_the_records():
    """Uneven records of a bird moving at 0.4 m/s on a belt slowing from 0.5
    to 0.3 m/s at t = 0.5 s: the frames are even, the state linear in time
    is met to rounding, and the belt's travel is the speed's integral
    (trapezoids are exact for a piecewise-linear speed sampled at its kink)."""
    t = np.array([0.0, 0.013, 0.05, 0.21, 0.5, 0.77, 1.0])
    columns = {"t_s": t, "X_m": -0.3 + 0.4 * t, "Z_m": 0.05 + 0 * t, "theta_rad": 0.1 * t,
               "Xdot_m_s": 0.4 + 0 * t, "Zdot_m_s": 0 * t, "thetadot_rad_s": 0.1 + 0 * t,
               "N_N": 10 * t, "belt_speed_m_s": np.interp(t, [0.0, 0.5, 1.0], [0.5, 0.5, 0.3])}
    states = frame_states(columns, 0.02)
    times = np.array(states["t_s"])
    assert len(times) == 51 and np.allclose(np.diff(times), 0.02)
    np.testing.assert_allclose(states["X_m"], -0.3 + 0.4 * times, atol=1e-15)
    np.testing.assert_allclose(states["N_N"], 10 * times, atol=1e-12)
    travel = np.where(times <= 0.5, 0.5 * times,
                      0.25 + 0.5 * (times - 0.5) - 0.2 * (times - 0.5) ** 2)
    # between records the travel is interpolated linearly: its error is at
    # most the speed's slope (0.4 m/s²) times the longest gap squared over 8
    np.testing.assert_allclose(states["belt_travel_m"], travel, atol=0.4 * 0.29 ** 2 / 8)


def test_fingers_solved_again_at_the_recorded_states_give_the_recorded_forces(short_run):
    """Every third recorded instant's state, the fingers solved again from
    the run's scene as the result keeps it (its scene file's content): each
    finger's force is the simulation's to 1e-6 N (both solve the same
    contact to the Newton tolerance, continued from different instants)."""
    rows = timeseries(short_run)[::3]
    record = animation_record({"short": (grasp_spec(short_run.setup, GraspSettings(
        LOOP.simulator, 6), "short", ""), rows)}, None)
    from design.io.scene import load_scene
    from design.run.grasp import setup_of

    scene = load_scene(record["runs"]["short"]["scene"])
    states = {k: [r[k] for r in rows] for k in ("t_s", *STATE, "N_N")}
    states["belt_travel_m"] = [0.0] * len(rows)
    run = solve_frames("short", setup_of(scene), scene.settings.contact_nodes, states, len(rows))
    names = run.names
    touched = 0
    for frame, row in zip(run.frames, rows):
        for name, force in zip(names, frame.forces):
            assert np.linalg.norm(force) == pytest.approx(row[f"F{name}_N"], abs=1e-6)
            touched += row[f"F{name}_N"] > 0
    assert touched > 10                     # the comparison saw contacts


def test_a_result_keeps_its_animation_and_design_animate_redraws_it(grasp_out, tmp_path):
    """result.json's animation: even frames over the run, the bird's state
    at each from the time series; ``design animate --out x.html`` writes
    the interactive view with plotly.js inlined."""
    result = json.loads((grasp_out / "result.json").read_text())
    record = result["animation"]
    (label, run), = record["runs"].items()
    states = run["states"]
    series = result["timeseries"]
    assert states["t_s"][-1] <= series["t_s"][-1] < states["t_s"][-1] + record["frame_step_s"]
    np.testing.assert_allclose(states["X_m"], np.interp(states["t_s"], series["t_s"],
                                                        series["X_m"]), atol=1e-12)
    out = tmp_path / "view.html"
    assert main(["animate", str(grasp_out), "--out", str(out), "--quiet"]) == 0
    page = out.read_text(encoding="utf-8")
    assert "Plotly.newPlot" in page and "plotly.js v" in page and "<script src=" not in page


def test_design_animate_refuses_what_it_cannot_draw(grasp_out, tmp_path, capsys, monkeypatch):
    """Exit 2, the file and field named, nothing written."""
    cases = [([str(tmp_path / "none")], "none/result.json: no such file"),
             ([str(grasp_out), "--out", str(tmp_path / "x.txt")], "--out")]
    beam = tmp_path / "beam"
    beam.mkdir()
    (beam / "result.json").write_text(json.dumps({"kind": "beam"}))
    cases.append(([str(beam)], "beam/result.json: kind: 'beam' has no animation"))
    old = tmp_path / "old"
    old.mkdir()
    result = json.loads((grasp_out / "result.json").read_text())
    result.pop("animation")
    (old / "result.json").write_text(json.dumps(result))
    cases.append(([str(old)], "old/result.json: animation: missing"))
    monkeypatch.setattr("design.report.video.ffmpeg_available", lambda: False)
    cases.append(([str(grasp_out), "--out", str(tmp_path / "x.mp4")], "MP4 needs ffmpeg"))
    for args, message in cases:
        assert main(["animate", *args, "--quiet"]) == 2
        assert message in capsys.readouterr().err
    with pytest.raises(SystemExit) as exited:
        main(["animate", str(grasp_out), "--speed", "0"])
    assert exited.value.code == 2 and "fraction of real time" in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["beam", "old"]


def test_a_gif_has_every_frame(grasp_out, tmp_path):
    """The video writer draws each frame of each run: a GIF of three frames
    played at 0.25x real time shows each for step / 0.25."""
    from PIL import Image

    record = json.loads((grasp_out / "result.json").read_text())["animation"]
    runs = animated_runs(record)
    for run in runs:
        run.frames = run.frames[10:13]
    path = tmp_path / "a.gif"
    write_video(runs, record["frame_step_s"], None, path, speed=0.25)
    with Image.open(path) as gif:
        assert gif.n_frames == 3
        assert gif.info["duration"] == pytest.approx(1e3 * record["frame_step_s"] / 0.25, abs=1)


def test_a_two_second_design_report_stays_under_8_mb(design_run):
    """Baseline and optimum of a 2 s run, MAX_FRAMES frames each (the short
    design's frames, repeated), with everything else the design report
    holds: under the budget."""
    _, out, _ = design_run
    record = json.loads((out / "result.json").read_text())["animation"]
    runs = animated_runs(record)
    report = (out / "report.html").stat().st_size
    own = len(animation_html(runs, record["frame_step_s"], record["cap_N"]).encode())
    for run in runs:
        run.frames = (run.frames * MAX_FRAMES)[:MAX_FRAMES]
    two_seconds = len(animation_html(runs, frame_step(2.0), record["cap_N"]).encode())
    assert report - own + two_seconds < REPORT_BUDGET


def _text_boxes(ax, renderer) -> list:
    """The window extents of an axes' texts: annotations, title, axis labels
    and the legend."""
    texts = [*ax.texts, ax.title, ax.xaxis.label, ax.yaxis.label]
    boxes = [(t.get_text(), t.get_window_extent(renderer)) for t in texts if t.get_text()]
    if ax.get_legend() is not None:
        boxes.append(("legend", ax.get_legend().get_window_extent(renderer)))
    return boxes


@pytest.mark.parametrize("figure", ["path", "layout"])
def test_no_two_labels_of_a_static_figure_overlap(short_run, figure):
    """In the side view the short grasp's first contact and hold start fall
    close together: their labels, the title, the axis labels and the
    legend of each axes do not intersect."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    fig = gf.path_figure(short_run) if figure == "path" else \
        gf.layout_figure({"baseline": short_run.setup, "other": short_run.setup})
    renderer = FigureCanvasAgg(fig).get_renderer()
    fig.draw_without_rendering()
    labelled = 0
    for ax in fig.axes:
        boxes = _text_boxes(ax, renderer)
        labelled += len(ax.texts)
        for (a, box_a), (b, box_b) in combinations(boxes, 2):
            assert not box_a.overlaps(box_b), (a, b)
    assert figure == "layout" or labelled >= 3          # the key instants were labelled


def test_a_finger_is_split_where_it_meets_the_belt():
    """A finger dipping 10 mm below the belt and back: the crossings are on
    the belt (Z = 0) where the segments cross it, the part drawn solid is
    nowhere below the belt and the dotted part nowhere above."""
    curve = np.array([[0.0, 0.01, 0.02, 0.03], [0.0] * 4, [0.01, -0.01, -0.01, 0.01]])
    above, below, crossings = gf.split_at_belt(curve)
    np.testing.assert_allclose(crossings, [[0.005, 0.025], [0.0, 0.0], [0.0, 0.0]], atol=1e-15)
    assert np.nanmin(above[2]) >= 0.0 and np.nanmax(below[2]) <= 0.0
    assert np.isnan(above[2]).sum() == 2 and np.isnan(below[2]).sum() == 2


#: Debian's Chromium, which the browser test drives (.ci/run installs it)
CHROMIUM = Path("/usr/bin/chromium")
#: flags for a machine with no network: no background connections, no GPU
CHROMIUM_FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
                  "--disable-component-update", "--disable-sync", "--no-first-run"]
#: the frames the browser test steps to (the short run's 0.1, 0.4 and 0.75 s)
STEPPED = (5, 20, 37)


def _browser():
    """Playwright's Chromium on /usr/bin/chromium, or a skip saying what is missing."""
    try:
        from playwright.sync_api import sync_playwright
    except ImportError:
        pytest.skip("playwright is not installed (pip install -e '.[test]')")
    if not CHROMIUM.exists():
        pytest.skip(f"no Chromium at {CHROMIUM} (apt-get install chromium; .ci/run does)")
    return sync_playwright


def _bird_pixels(png: bytes) -> np.ndarray:
    """The (column, row) of every pixel of the bird, drawn pure red."""
    import io

    from PIL import Image

    rgb = np.asarray(Image.open(io.BytesIO(png)).convert("RGB")).astype(int)
    rows, cols = np.nonzero((rgb[..., 0] > 200) & (rgb[..., 1] < 60) & (rgb[..., 2] < 60))
    return np.column_stack([cols, rows])


@pytest.mark.both_cores
def test_the_report_plays_offline_and_draws_the_bird_where_the_time_series_puts_it(design_run):
    """The design report in headless Chromium: it loads with no console
    error and no request beyond its own file; stepped to three frames and
    seen from the side (orthographic, along Y, the optimum's bird alone and
    red), the bird's centre moves on the screen as timeseries.csv's X and Z
    do between those frames, at the scale its own drawn length gives
    (within 2 px and 2 %: the silhouette's edge pixels)."""
    sync_playwright = _browser()
    _, out, _ = design_run
    result = json.loads((out / "result.json").read_text())
    states = result["animation"]["runs"]["optimum"]["states"]
    series = np.genfromtxt(out / "timeseries.csv", delimiter=",", names=True)
    errors, foreign = [], []
    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=str(CHROMIUM), args=CHROMIUM_FLAGS)
        page = browser.new_page(viewport={"width": 1300, "height": 900})
        page.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
        page.on("pageerror", lambda e: errors.append(str(e)))

        def route(r):
            if r.request.url.startswith(("file:", "data:")):
                return r.continue_()
            foreign.append(r.request.url)
            return r.abort()

        page.route("**/*", route)
        page.goto((out / "report.html").as_uri(), wait_until="load")
        page.wait_for_function("document.getElementById('animation-view')?._fullLayout")
        traces = page.evaluate("document.getElementById('animation-view').data.map("
                               "t => [t.scene || 'scene', t.name || ''])")
        bird = next(i for i, (scene, name) in enumerate(traces)
                    if scene == "scene2" and name == "bird")
        others = [i for i in range(len(traces)) if i != bird]
        page.evaluate(f"""Plotly.restyle('animation-view', {{visible: false}}, {others}).then(() =>
            Plotly.restyle('animation-view', {{colorscale: [[[0, '#ff0000'], [1, '#ff0000']]],
              lighting: {{ambient: 1, diffuse: 0, specular: 0, fresnel: 0}}}}, [{bird}]))
            .then(() => Plotly.relayout('animation-view', {{
              'scene2.camera': {{eye: {{x: 0, y: -2, z: 0}}, up: {{x: 0, y: 0, z: 1}},
                                 center: {{x: 0, y: 0, z: 0}},
                                 projection: {{type: 'orthographic'}}}},
              'scene2.xaxis.range': [-600, 600]}}))
            .then(() => {{  // one scale on every axis
              const s = document.getElementById('animation-view')._fullLayout.scene2;
              const size = a => s[a].range[1] - s[a].range[0];
              return Plotly.relayout('animation-view', {{'scene2.aspectratio': {{
                x: size('xaxis') / 400, y: size('yaxis') / 400, z: size('zaxis') / 400}}}});
            }})""")
        seen = []
        for k in STEPPED:
            page.evaluate(f"Plotly.animate('animation-view', ['{k}'], {{mode: 'immediate', "
                          "frame: {duration: 0, redraw: true}, transition: {duration: 0}})"
                          ".then(() => new Promise(done => requestAnimationFrame("
                          "() => requestAnimationFrame(done))))")
            shot = page.locator("#animation-view").screenshot()
            seen.append(_bird_pixels(shot))
        browser.close()
    assert errors == [] and foreign == []
    bird_setup = short_setup().bird
    t = np.array(states["t_s"])[list(STEPPED)]
    x, z, pitch = (np.interp(t, series["t_s"], series[c]) for c in ("X_m", "Z_m", "theta_rad"))
    # the silhouette's length along X: the pitched X-Z ellipse's extent
    length = 2 * np.sqrt((bird_setup.eta * np.cos(pitch)) ** 2 +
                         (bird_setup.gamma * np.sin(pitch)) ** 2)
    scale = np.mean([(px[:, 0].max() - px[:, 0].min()) / d for px, d in zip(seen, length)])
    centres = np.array([px.mean(axis=0) for px in seen])
    for a, b in combinations(range(3), 2):
        moved = scale * np.array([x[b] - x[a], -(z[b] - z[a])])
        np.testing.assert_allclose(centres[b] - centres[a], moved, atol=2 + 0.02 * abs(moved[0]))
    # the bird moved far across the screen between the first and the last frame
    assert abs(scale * (x[2] - x[0])) > 100
