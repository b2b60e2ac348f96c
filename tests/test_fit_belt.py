"""design fit, target belt: a belt speed profile from an encoder log.

The shipped Figure 5-10 log (examples/fit/figure_5_10_belt.csv) is built from
the thesis's stated values with noise 0.005 m/s (its header says how); the
fit must return them within 3 standard errors (of the fit's own, from the
residuals), and the conveyor file it writes must load as the toolkit's
conveyor and give the same speeds.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import yaml

from design.api import fit
from design.cli import main
from design.calibration.belt import monotone_fit, ramp, ramp_fit
from design.io.grasp_scene import read_conveyor
from design.io.reader import Reader

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "examples" / "fit" / "belt_figure_5_10.yaml"
#: what the log was built from (the thesis's 0.457 and 0.254 m/s, the slow-down at
#: 0.4 s into the cycle, the model file's assumed 2 m/s^2)
BUILT = {"speed": 0.457, "final_speed": 0.254, "start_time": 0.4, "rate": 2.0}
NOISE = 0.005


@pytest.fixture(scope="module")
def figure_5_10(tmp_path_factory):
    out = tmp_path_factory.mktemp("belt")
    assert main(["fit", str(EXAMPLE), "--out", str(out), "--quiet"]) == 0
    return out, yaml.safe_load((out / "result.json").read_text())


def test_figure_5_10_profile_is_recovered_within_its_standard_errors(figure_5_10):
    _, r = figure_5_10
    assert r["decelerates"] and r["ok"]
    for key, value in BUILT.items():
        assert abs(r["fitted"][key] - value) <= 3 * r["standard_errors"][key], key
    # the residuals are the log's noise, for both fits
    assert r["ramp"]["rms"] == pytest.approx(NOISE, rel=0.15)
    assert r["monotone"]["rms"] <= r["ramp"]["rms"]
    assert r["monotone"]["rms"] == pytest.approx(NOISE, rel=0.15)
    stated = {c["quantity"]: c for c in r["comparison"]}
    assert stated["speed"]["stated"] == pytest.approx(18 * 0.0254)    # 18 in/s as written
    assert set(stated) == {"speed", "final_speed", "start_time", "rate"}


def test_the_conveyor_file_loads_and_gives_the_fitted_speeds(figure_5_10):
    out, r = figure_5_10
    reader = Reader("conveyor.yaml")
    conveyor = read_conveyor(reader, str(out / "conveyor.yaml"), "conveyor", ROOT)
    assert reader.ok and conveyor.decelerates
    start = conveyor.start_time
    for t in (0.0, 0.45, 1.0):                      # before, on and after the ramp
        expected = ramp(np.array([t]), r["fitted"]["speed"], r["fitted"]["final_speed"],
                        r["fitted"]["start_time"], r["fitted"]["end_time"])[0]
        assert conveyor.velocity(t, start)[0] == pytest.approx(expected, abs=1e-9)


def test_the_data_file_says_it_was_constructed_and_how():
    header = (ROOT / "examples" / "fit" / "figure_5_10_belt.csv").read_text().split("t [s]")[0]
    for words in ("CONSTRUCTED from the thesis's stated values, not digitised", "seed 510",
                  "2 m/s^2", "0.005 m/s"):
        assert words in header


def test_a_constant_belt_is_fitted_as_constant(tmp_path):
    """No slow-down in the log: none is fitted (the drop is within noise) and
    the conveyor file has one speed."""
    t = np.arange(0.0, 1.0, 0.01)
    v = 0.457 + NOISE * np.random.default_rng(3).standard_normal(t.size)
    rows = "t [ms],v [in/s]\n" + "".join(f"{a * 1e3:.1f},{b / 0.0254:.6f}\n" for a, b in zip(t, v))
    (tmp_path / "log.csv").write_text(rows)
    result = fit({"kind": "fit", "target": "belt", "data": str(tmp_path / "log.csv")},
                 out=tmp_path / "out")
    record = result.to_dict()
    assert result.status == "fitted" and not record["decelerates"]
    assert record["fitted"]["speed"] == pytest.approx(0.457, abs=3 * NOISE / np.sqrt(t.size))
    spec = yaml.safe_load(result.model_file.read_text())
    assert "final_speed" not in spec and spec["speed"] == pytest.approx(record["fitted"]["speed"])


def test_the_monotone_fit_is_non_increasing_and_the_ramp_fit_finds_a_sharp_ramp():
    t = np.linspace(0.0, 1.0, 201)
    v = ramp(t, 0.5, 0.2, 0.3, 0.45)
    mono = monotone_fit(t, v + 0.002 * np.random.default_rng(1).standard_normal(t.size), 41)
    assert np.all(np.diff(mono.speeds) <= 1e-9)
    exact = ramp_fit(t, v)                          # noise-free: exact parameters
    assert (exact.v0, exact.v1, exact.t_start, exact.t_end) == pytest.approx(
        (0.5, 0.2, 0.3, 0.45), abs=1e-6)
    assert exact.rate == pytest.approx(2.0, rel=1e-5)
