"""report.html for every kind of run: every promised section and figure is
there, every figure is an embedded, non-empty PNG, and the tables say what
result.json says."""

from __future__ import annotations

import base64
import html
import json
from html.parser import HTMLParser
from pathlib import Path

import numpy as np
import pytest

from design.cli import main
from design.io.grasp_scene import GraspSettings
from design.io.scene_writer import grasp_spec, scene_yaml
from design.report import write_run
from design.report.design import design_page
from design.report.grasp_figures import finger_curves
from design.report.page import write_report
from design.run import RunOutput
from design.solvers.contact.spatial import Quadric, SpatialContact
from design.solvers.grasp.fingers import FingerState
from design.solvers.optimize.model_check import compare
from tests.design_cases import LOOP, shared_simulate_grasp, sharing_simulations, short_setup

PROBLEMS = Path(__file__).parent.parent / "problems"
PNG = b"\x89PNG\r\n\x1a\n"


class Report(HTMLParser):
    """The parts of a report the tests look at: section ids, figures (id ->
    PNG bytes), tables (id -> rows of cell text) and the banner."""

    def __init__(self, text: str):
        super().__init__()
        self.sections, self.figures, self.tables, self.banner = [], {}, {}, None
        self._figure = self._table = self._row = self._cell = self._banner = None
        self.feed(text)

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if tag == "h2":
            self.sections.append(a.get("id"))
        elif tag == "figure":
            self._figure = a["id"]
        elif tag == "img" and self._figure:
            head, data = a["src"].split(",", 1)
            assert head == "data:image/png;base64"
            self.figures[self._figure] = base64.b64decode(data)
        elif tag == "table":
            self._table = a.get("id", f"table-{len(self.tables)}")
            self.tables[self._table] = []
        elif tag == "tr" and self._table:
            self._row = []
        elif tag in ("td", "th") and self._row is not None:
            self._cell = ""
        elif tag == "div" and "banner" in a.get("class", ""):
            self._banner, self.banner = a["class"], ""

    def handle_endtag(self, tag):
        if tag == "figure":
            self._figure = None
        elif tag == "table":
            self._table = None
        elif tag == "tr" and self._row is not None:
            self.tables[self._table].append(self._row)
            self._row = None
        elif tag in ("td", "th") and self._cell is not None:
            self._row.append(self._cell)
            self._cell = None
        elif tag == "div" and self._banner:
            self._banner = None

    def handle_data(self, data):
        if self._cell is not None:
            self._cell += data
        if self._banner is not None:
            self.banner += data

    def column(self, table: str, name: str) -> list[str]:
        head, *rows = self.tables[table]
        return [r[head.index(name)] for r in rows]


def read(out: Path) -> Report:
    report = Report((out / "report.html").read_text(encoding="utf-8"))
    for name, png in report.figures.items():
        assert png.startswith(PNG) and len(png) > 5000, name       # a real picture
        assert (out / "figures" / f"{name.removeprefix('fig-')}.png").read_bytes() == png
    return report


def close(cell: str, value: float, digits: int = 4) -> bool:
    """A table cell rounded to ``digits`` significant figures matches value."""
    return float(cell) == pytest.approx(value, rel=10 ** (1 - digits), abs=1e-12)


def test_beam_report(tmp_path):
    assert main(["simulate", str(PROBLEMS / "beam_table_2_3.yaml"), "--out", str(tmp_path),
                 "--quiet"]) == 0
    r, result = read(tmp_path), json.loads((tmp_path / "result.json").read_text())
    assert r.sections == ["scene", "deflection", "reproduce"]
    assert list(r.figures) == ["fig-deflection"]
    assert r.banner == "All 1 loads converged"
    tip_y = r.column("cases-table", "tip y (m)")
    assert len(tip_y) == len(result["cases"])
    assert all(close(c, case["tip"]["y"], 6) for c, case in zip(tip_y, result["cases"]))
    # angles in degrees, as the scene gives them (result.json keeps radians)
    assert r.column("cases-table", "α (°)") == ["90"] and result["cases"][0]["alpha"] == \
        pytest.approx(np.pi / 2)


def test_contact_report(tmp_path):
    assert main(["simulate", str(PROBLEMS / "contact_pass.yaml"), "--out", str(tmp_path),
                 "--quiet"]) == 0
    r, result = read(tmp_path), json.loads((tmp_path / "result.json").read_text())
    assert r.sections == ["scene", "forces", "reproduce"] and list(r.figures) == ["fig-contact"]
    forces = r.column("cases-table", "force (N)")
    assert all(close(c, case["force"]) for c, case in zip(forces, result["cases"]))
    assert r.banner.startswith(f"All {len(result['cases'])} poses converged")
    angles = r.column("cases-table", "finger angle (°)")
    assert all(close(c, np.degrees(case["finger_angle"])) for c, case in zip(angles,
                                                                             result["cases"]))


GRASP_SECTIONS = ["layout", "path", "normal-force", "finger-forces", "contact-loci"]
GRASP_FIGURES = ["fig-layout", "fig-path", "fig-normal_force", "fig-finger_forces",
                 "fig-contact_loci"]


def short_scene(tmp_path) -> Path:
    """The short grasp as a scene file integrated as the design loop does
    (LOOP.simulator), so that its simulation is also the design run's and
    the optimiser tests' baseline: one run for all (tests/design_cases.py)."""
    path = tmp_path / "short.yaml"
    path.write_text(scene_yaml(grasp_spec(short_setup(), GraspSettings(LOOP.simulator, 6),
                                          "short", "the short grasp")))
    return path


def test_grasp_report(tmp_path):
    with sharing_simulations():
        assert main(["simulate", str(short_scene(tmp_path)), "--out", str(tmp_path / "out"),
                     "--quiet"]) == 0
    out = tmp_path / "out"
    r, result = read(out), json.loads((out / "result.json").read_text())
    assert r.sections == ["scene", "summary", "animation", *GRASP_SECTIONS, "reproduce"]
    assert list(r.figures) == GRASP_FIGURES
    s = result["summary"]
    rows = dict(zip(r.column("summary-table", "quantity"), r.column("summary-table", "value")))
    assert close(rows["longest N = 0 hold"], s["hold_time_s"])
    assert close(rows["peak finger force"], s["max_finger_force_N"])
    assert rows["finger with the peak"] == s["max_finger_force_finger"]
    assert close(rows["largest pitch"], np.degrees(s["max_pitch_rad"]))
    fingers = r.tables["table-0"]
    angle = fingers[0].index("angle")
    assert [close(row[angle], np.degrees(f["angle"])) for row, f in
            zip(fingers[1:], result["grasper"]["fingers"])] == [True] * (len(fingers) - 1)


#: the prefetch key of :func:`solve_short_design`
DESIGN_RUN = "tests/test_reports.py: the short design solve"


class RecordingCheck:
    """The spatial model check's interface (design/solvers/optimize/model_check.py)
    without its spatial runs (12 s of CPU on the short grasp, in a third
    process beside the test process and the prefetch worker): it records the
    designs the run hands it and answers with made-up runs, the optimum's
    longer and lighter. The real background runs are tests/test_model_check.py's."""

    submitted: list = []

    def __init__(self, integrator):
        self.integrator = integrator

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        pass

    def submit(self, label, population, d):
        RecordingCheck.submitted.append((label, np.asarray(d, float).tolist()))

    def result(self, population, cap_spec, baseline="baseline", optimum="optimum"):
        def run(hold, peak):
            return {"hold_time_s": hold, "max_finger_force_N": peak,
                    "max_finger_force_finger": "1a", "model_warnings": [], "cpu_time_s": 0.0,
                    "ok": True}
        return compare(population, cap_spec, [run(0.30, 20.0)], [run(0.31, 19.0)],
                       self.integrator)


def solve_short_design(tmp: Path) -> tuple[int, list]:
    """One short design solve (one outer iteration) written with its report
    to tmp/out; its exit status and the designs it handed the model check
    (:class:`RecordingCheck`). Its simulations are shared with the other
    tests' (tests/design_cases.py)."""
    problem = {"kind": "design", "name": "short_design", "description": "A short test.",
               "scene": str(short_scene(tmp)), "cap": "baseline",
               "variables": {"groups.upper.stiffness_scale": [0.5, 1.5]},
               "solver": {"time_step": 0.01, "max_iter": 15, "outer_iterations": 1}}
    path = tmp / "problem.yaml"
    path.write_text(json.dumps(problem))
    RecordingCheck.submitted = []
    with sharing_simulations(), pytest.MonkeyPatch.context() as patch:
        patch.setattr("design.run.solve.ModelCheck", RecordingCheck)
        status = main(["solve", str(path), "--out", str(tmp / "out"), "--quiet"])
    return status, RecordingCheck.submitted


def test_design_report_has_every_section_and_matches_result(design_run):
    status, out, checked = design_run
    r, result = read(out), json.loads((out / "result.json").read_text())
    check_ran = result["status"] in ("verified", "failed verification")  # an optimum to check
    assert r.sections == ["problem", "verification", "animation", *GRASP_SECTIONS,
                          *(["model-check"] if check_ran else []), "convergence", "reproduce"]
    assert list(r.figures) == GRASP_FIGURES + ["fig-convergence"]
    passed = result["verification"]["passed"]
    assert (status == 0) == passed
    assert r.banner.startswith("VERIFIED" if passed else "FAILED")
    names = r.column("variables-table", "variable")
    assert names == [v["name"] for v in result["variables"]]
    for column, key in [("lower", "lower"), ("upper", "upper"), ("baseline", "baseline"),
                        ("optimum", "optimum")]:
        cells = r.column("variables-table", column)
        assert all(close(c, v[key] * (180 / np.pi if v["unit"] == "rad" else 1.0))
                   for c, v in zip(cells, result["variables"]))
    v = result["verification"]
    checks = r.column("verification-table", "independent simulation")
    assert close(checks[0], v["hold_time_s"]) and close(checks[1], v["max_finger_force_N"])
    optimiser = r.column("verification-table", "optimiser or limit")
    assert close(optimiser[0], v["optimiser_hold_time_s"]) and close(optimiser[1], v["cap_N"])
    assert len(r.tables["history-table"]) - 1 == len(result["solver"]["history"])
    # the spatial model check: handed the baseline at the start and the
    # reported optimum; both runs in the report's table, the cap's rule (the
    # baseline's peak) resolved on the spatial baseline
    variables = result["variables"]
    scaled = [(v["baseline"] - v["lower"]) / (v["upper"] - v["lower"]) for v in variables]
    assert checked[0] == ("baseline", pytest.approx(scaled))
    if check_ran:
        optimum = [(v["optimum"] - v["lower"]) / (v["upper"] - v["lower"]) for v in variables]
        assert checked[1] == (result["case"], pytest.approx(optimum, abs=1e-12))
        check = result["model_check"]
        bird = check["birds"][0]
        holds = r.column("model-check-table", "hold (s)")
        assert close(holds[0], bird["baseline"]["hold_time_s"])
        assert close(holds[1], bird["optimum"]["hold_time_s"])
        assert bird["cap_N"] == bird["baseline"]["max_finger_force_N"]
        assert check["gain_survives"] and "the gain survives" in r.banner
    else:
        assert result["model_check"] is None and len(checked) == 1


def test_design_report_draws_the_pareto_curve(design_run, tmp_path):
    """With a Pareto study the report adds its table and curve (the study's
    rows here are made up; the page only draws them; the runs drawn are the
    short grasp's, the design run's own baseline)."""
    _, out, _ = design_run
    result = json.loads((out / "result.json").read_text())
    result["pareto"] = [{"cap_N": c, "status": "verified", "optimiser_hold_time_s": h,
                         "verified_hold_time_s": h, "verified_max_finger_force_N": c - 1,
                         "passed": True} for c, h in [(10.0, 0.1), (12.0, 0.2)]]
    run = shared_simulate_grasp(short_setup(), LOOP.simulator)
    write_report(tmp_path, design_page(result, run, run))
    r = read(tmp_path)
    assert "pareto" in r.sections and "fig-pareto" in r.figures
    assert [float(c) for c in r.column("pareto-table", "cap_N")] == [10.0, 12.0]


def test_a_report_is_written_whole_or_not_at_all(tmp_path, monkeypatch):
    """An error while the report is being built leaves nothing behind: the
    page is rendered in memory before any file is written."""
    output = RunOutput({"kind": "beam", "name": "x"})

    def broken(result):
        raise KeyboardInterrupt

    monkeypatch.setattr("design.report.beam_contact.beam_page", broken)
    with pytest.raises(KeyboardInterrupt):
        write_run(tmp_path / "out", output)
    assert not (tmp_path / "out").exists()


def test_finger_curves_draw_a_spatial_rod_whole():
    """A spatial contact's finger is drawn from its rod points: the curve starts
    at the finger's base and, the rod being inextensible, its polyline is as
    long as the finger (1 %: the chord error of the collocation points)."""
    setup = short_setup()
    gf = setup.grasper.fingers[0]
    quadric = Quadric(np.array([0.6 * gf.finger.length, 0.045, 0.01]),
                      np.diag([1 / 0.06 ** 2, 1 / 0.05 ** 2, 1 / 0.05 ** 2]))
    sol, _ = SpatialContact(gf.finger).solve(quadric)
    assert sol.contact and sol.converged
    states = [FingerState(solution=sol)] + [FingerState()] * (len(setup.grasper.fingers) - 1)
    curves = finger_curves(setup, 0.3, states)
    base, R = setup.grasper.drum(setup.drum_speed).frame(gf.mount, 0.3)
    np.testing.assert_allclose(curves[0], base[:, None] + R @ sol.shape_points, atol=1e-15)
    length = np.sum(np.linalg.norm(np.diff(curves[0], axis=1), axis=0))
    assert length == pytest.approx(gf.finger.length, rel=0.01)
    assert curves[1].shape[1] == 2          # no contact: the straight finger's two ends


def test_design_variables_are_shown_in_degrees():
    """A finger angle's bounds, baseline, optimum and change are shown in
    degrees, as the problem file gives them; a stiffness scale as it is."""
    from design.report.design import shown_design, variable_rows

    angle = {"name": "fingers.4.angle", "unit": "rad", "lower": np.radians(100.5),
             "upper": np.radians(124.5), "baseline": np.radians(112.5),
             "optimum": np.radians(113.0), "active_bound": ""}
    scale = {**angle, "name": "groups.lower.stiffness_scale", "unit": "", "lower": 0.5,
             "upper": 2.0, "baseline": 1.0, "optimum": 2.0, "active_bound": "upper"}
    rows = variable_rows([angle, scale])
    assert rows[0] == {"variable": "fingers.4.angle", "unit": "deg",
                       "lower": pytest.approx(100.5), "upper": pytest.approx(124.5),
                       "baseline": pytest.approx(112.5), "optimum": pytest.approx(113.0),
                       "change": pytest.approx(0.5), "active bound": ""}
    assert rows[1]["unit"] == "" and rows[1]["optimum"] == 2.0 and rows[1]["change"] == 1.0
    starts = shown_design({"start": 0, "fingers.4.angle": np.pi / 2,
                           "groups.lower.stiffness_scale": 1.5, "conveyor.start_time": 0.2})
    assert starts == {"start": 0, "fingers.4.angle (deg)": pytest.approx(90.0),
                      "groups.lower.stiffness_scale": 1.5, "conveyor.start_time (s)": 0.2}


def test_the_search_table_says_where_and_why_a_candidate_s_run_ended():
    """A pattern search's history with a candidate taken, one whose run a
    finger over its limit ended (no hold or peak given: they would be the
    run's up to there) and one ruled out by its whole run."""
    from design.report.design import search_table
    from design.report.page import Page
    step = {"radius": 0.125, "variable": "conveyor.rate", "move": "poll"}
    solver = {"search": {"rtol": 1e-6, "first_step": 0.125, "lattice": 1 / 64,
                         "hold_band_s": 1e-4, "simulations": 4, "max_simulations": 150,
                         "lattice_optimum": True, "bird_simulations": 4},
              "history": [
                  {"iteration": 1, **step, "simulated_hold_time_s": 0.41,
                   "simulated_peak_force_N": 19.1, "accepted": True, "ruled_out_by": None,
                   "stopped": None},
                  {"iteration": 2, **step, "simulated_hold_time_s": 0.0,
                   "simulated_peak_force_N": 19.7, "accepted": False,
                   "ruled_out_by": "mean-bird-1.80kg",
                   "stopped": "finger 5b pressed 19.70 N, over its limit 19.60 N, at 1.143 s"},
                  {"iteration": 3, **step, "simulated_hold_time_s": 0.39,
                   "simulated_peak_force_N": 18.2, "accepted": False,
                   "ruled_out_by": "mean-bird-1.80kg", "stopped": None}]}
    page = Page("search")
    search_table(page, solver)
    r = Report(page.render())
    assert r.column("history-table", "simulated hold (s)") == ["0.41", "—", "0.39"]
    assert r.column("history-table", "simulated peak (N)") == ["19.1", "—", "18.2"]
    assert r.column("history-table", "ruled out by") == [
        "", "finger 5b pressed 19.70 N, over its limit 19.60 N, at 1.143 s", "its whole run"]


def test_the_search_table_says_which_surveyed_design_the_search_started_from():
    """Two surveyed designs, the second taken, then a poll: the text names
    the survey and the simulation the search started from; the survey's
    rows have no step."""
    from design.report.design import search_table
    from design.report.page import Page
    survey = {"radius": 0.0, "variable": None, "move": "survey", "ruled_out_by": None,
              "stopped": None, "simulated_peak_force_N": 18.0}
    solver = {"search": {"rtol": 1e-6, "first_step": 0.125, "lattice": 1 / 32,
                         "hold_band_s": 1e-4, "simulations": 4, "max_simulations": 4,
                         "lattice_optimum": False, "bird_simulations": 4, "survey": 2},
              "history": [
                  {"iteration": 1, **survey, "simulated_hold_time_s": 0.30, "accepted": False},
                  {"iteration": 2, **survey, "simulated_hold_time_s": 0.50, "accepted": True},
                  {"iteration": 3, "radius": 0.125, "variable": "conveyor.rate",
                   "move": "poll", "simulated_hold_time_s": 0.52, "simulated_peak_force_N": 18.5,
                   "accepted": True, "ruled_out_by": None, "stopped": None}]}
    page = Page("search")
    search_table(page, solver)
    rendered = page.render()
    text = html.unescape(rendered)
    assert "first a survey of 2 points of a scrambled Sobol sequence" in text
    assert "starting from the best of them (simulation 2)" in text
    assert "the survey's included, the budget ending the search" in text
    r = Report(rendered)
    assert r.column("history-table", "step (scaled)") == ["—", "—", "0.125"]
    assert r.column("history-table", "move") == ["survey", "survey", "poll"]
