"""design fit's input: bad fit files and bad data are rejected with exit
status 2, each problem naming the file, the field or row and the accepted
range, and nothing is written; design check reads fit files."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml

from design.api import check
from design.cli import main

ROOT = Path(__file__).resolve().parents[1]
HEADER = "F [N],alpha [deg],at [mm],s [mm],y [mm]"
GOOD_ROWS = [f"1,90,200,{s},{s / 100:.3f}" for s in range(20, 201, 20)]


def _problem(tmp_path, rows, header=HEADER, extra=None, target="finger"):
    (tmp_path / "bench.csv").write_text("# a comment line\n" + "\n".join([header, *rows]) + "\n")
    spec = {"kind": "fit", "target": target, "data": "bench.csv"}
    if target == "finger":
        spec["finger"] = {"length": "203 mm"}
    spec.update(extra or {})
    path = tmp_path / "fit.yaml"
    path.write_text(yaml.safe_dump(spec))
    return path


def _rejected(tmp_path, capsys, path) -> str:
    out = tmp_path / "out"
    assert main(["fit", str(path), "--out", str(out), "--quiet"]) == 2
    assert not out.exists()
    err = capsys.readouterr().err
    assert "nothing was written" in err
    return err


def test_a_negative_load_is_rejected_naming_the_row_and_the_range(tmp_path, capsys):
    rows = GOOD_ROWS[:3] + ["-2,90,200,80,0.8"] + GOOD_ROWS[4:]
    err = _rejected(tmp_path, capsys, _problem(tmp_path, rows))
    assert f"{tmp_path / 'bench.csv'}: line 6, F: -2 N is outside the accepted range [0, inf) N" \
        in err


def test_points_beyond_the_finger_are_rejected(tmp_path, capsys):
    rows = GOOD_ROWS + ["1,90,250,210,2.1"]
    err = _rejected(tmp_path, capsys, _problem(tmp_path, rows))
    assert "line 13, at: 0.25 m is outside the accepted range (0, 0.203] m (the finger is " \
           "0.203 m long)" in err
    assert "line 13, s: 0.21 m is outside the accepted range (0, 0.203] m" in err


def test_a_deflection_larger_than_its_arc_length_is_rejected(tmp_path, capsys):
    """The default position noise is 0.5 mm: 60 mm at s = 50 mm is 20 σ past the bound."""
    err = _rejected(tmp_path, capsys, _problem(tmp_path, GOOD_ROWS + ["1,90,200,50,60"]))
    assert "line 13, y: |0.06| m is more than the point's arc length s = 0.05 m by 20 standard " \
           "deviations of the stated noise (fit.noise.position = 0.0005 m): accepted range " \
           "[-0.0525, 0.0525] m" in err


NOISY = {"fit": {"noise": {"position": "0.1 mm", "slope": "0.5 deg"}}}
X_HEADER = "F [N],alpha [deg],at [mm],s [mm],x [mm],y [mm],psi [deg]"
#: readings of a nearly straight finger: x within noise of s
X_ROWS = [f"0.5,90,100,{s},{s - 0.01:.4f},{s / 200:.4f}," for s in (25, 50, 75, 100)] * 2


def test_readings_within_noise_of_their_physical_bound_are_accepted_and_counted(tmp_path):
    """A camera reads a marker of a nearly straight finger a fraction of its
    0.1 mm noise past x = s: readings up to 5 σ past a bound (0.49 mm here,
    and a slope 2.4 deg past 180 deg with 0.5 deg noise) are noise, accepted
    as read; the warning counts the rows and gives the largest excess."""
    rows = X_ROWS + ["0.5,90,100,25,25.49,0,", "0.5,90,100,100,99.99,2,",
                     "0.5,90,100,100,,,-182.4"]
    problem = check(_problem(tmp_path, rows, header=X_HEADER, extra=NOISY)).value
    note = problem.data.note
    assert note.startswith("3 row(s) read a point farther from the clamp than its arc length s")
    assert "by up to 4.9 standard deviations" in note and "lines 11, 12, 13)" in note
    x = [o.value for o in problem.data.observations if o.line == 11 and o.quantity == "x"]
    assert x == [pytest.approx(0.02549)]                      # fitted as read, not clipped
    assert check(_problem(tmp_path, X_ROWS, header=X_HEADER, extra=NOISY)).value.data.note is None


@pytest.mark.parametrize("row, message", [
    ("0.5,90,100,25,25.51,0,", "line 11, x: |0.02551| m is more than the point's arc length "
                               "s = 0.025 m by 5.1 standard deviations of the stated noise "
                                "(fit.noise.position = 0.0001 m): accepted range "
                                "[-0.0255, 0.0255] m"),
    ("0.5,90,100,25,-25.6,,", "line 11, x: |-0.0256| m is more than"),
    ("0.5,90,100,100,99.9,12,", "line 11, x, y: the distance from the clamp sqrt(x² + y²) = "
                                "0.100618 m is more than the point's arc length s = 0.1 m by "
                                "6.18 standard"),
    ("0.5,90,100,100,20,99.6,", "line 11, x, y: the distance from the clamp"),
    ("0.5,90,100,100,,,183", "line 11, psi: |3.19395| rad is more than half a turn, 3.14159 "
                             "rad by 6 standard deviations of the stated noise "
                             "(fit.noise.slope = 0.00872665 rad)"),
])
def test_readings_past_their_bound_by_more_than_the_noise_allows_are_refused(
        tmp_path, capsys, row, message):
    """Past 5 σ of the stated noise a reading cannot be a true value within
    its physical bound (a chance below 3e-7): refused, naming the row, the
    column and the accepted range; nothing is written."""
    err = _rejected(tmp_path, capsys, _problem(tmp_path, X_ROWS + [row], header=X_HEADER,
                                               extra=NOISY))
    assert f"bench.csv: {message}" in err


def test_the_small_deflection_model_is_not_asked_to_fit_x_alone(tmp_path, capsys):
    """x readings alone: the small-deflection model has nothing to fit (x = s
    to first order), so asking for it is bad input, named by its field."""
    rows = [f"0.5,90,100,{s},{s - 0.01:.4f},," for s in (25, 50, 75, 100)] * 2
    extra = {"fit": {"method": "small-deflection", "noise": {"position": "0.1 mm"}}}
    err = _rejected(tmp_path, capsys, _problem(tmp_path, rows, header=X_HEADER, extra=extra))
    assert "fit.yaml: fit.method: small-deflection fits y and psi readings, and bench.csv has " \
           "only x" in err


def test_too_few_points_are_rejected(tmp_path, capsys):
    err = _rejected(tmp_path, capsys, _problem(tmp_path, GOOD_ROWS[:4]))
    assert "bench.csv: too few points: 4 measured values (x, y or psi); a finger fit needs " \
           "at least 6" in err


@pytest.mark.parametrize("header, message", [
    ("F [mm],alpha [deg],at [mm],s [mm],y [mm]",
     "column 'F [mm]': unit 'mm' is not a force (expected something like 'N'); this column is "
     "a force"),
    ("F [N],alpha [deg],at [mm],s [mm],y",
     "column 'y': no unit: write it in brackets, e.g. 'y [m]'"),
    ("F [N],alpha [deg],at [mm],s [s],y [mm]", "column 's [s]': unit 's' is not a length"),
])
def test_inconsistent_units_are_rejected_naming_the_column(tmp_path, capsys, header, message):
    err = _rejected(tmp_path, capsys, _problem(tmp_path, GOOD_ROWS, header=header))
    assert f"bench.csv: line 2, {message}" in err


def test_settings_are_checked_with_a_hint(tmp_path, capsys):
    path = _problem(tmp_path, GOOD_ROWS, extra={"fit": {"knot": 21, "monotone": "down"}})
    err = _rejected(tmp_path, capsys, path)
    assert "fit.yaml: fit.knot: unknown key" in err and "did you mean 'knots'?" in err
    assert "fit.monotone: 'down' is not one of: none, decreasing, increasing" in err


def test_a_missing_data_file_is_named(tmp_path, capsys):
    path = tmp_path / "fit.yaml"
    path.write_text(yaml.safe_dump({"kind": "fit", "target": "belt", "data": "nowhere.csv"}))
    err = _rejected(tmp_path, capsys, path)
    assert "data: data file 'nowhere.csv' not found" in err


def test_belt_times_must_increase_and_speeds_be_positive(tmp_path, capsys):
    rows = [f"{t / 100:.2f},0.457" for t in range(10)] + ["0.05,0.4", "0.2,-0.1"]
    err = _rejected(tmp_path, capsys, _problem(tmp_path, rows, header="t [s],v [m/s]",
                                               target="belt"))
    assert "bench.csv: line 13, t: 0.05 s does not come after the previous row's 0.09 s" in err
    assert "bench.csv: line 14, v: -0.1 m/s is outside the accepted range [0, inf) m/s" in err


def test_design_check_reads_fit_files_and_simulate_points_to_fit(tmp_path, capsys):
    assert main(["check", str(ROOT / "examples" / "fit" / "finger_bench.yaml"),
                 str(ROOT / "examples" / "fit" / "belt_figure_5_10.yaml")]) == 0
    assert main(["simulate", str(ROOT / "examples" / "fit" / "belt_figure_5_10.yaml"),
                 "--out", str(tmp_path / "x")]) == 2
    assert "run it with 'design fit'" in capsys.readouterr().err
    assert not (tmp_path / "x").exists()
    problems = check(_problem(tmp_path, GOOD_ROWS[:3] + ["-2,90,200,80,0.8"] + GOOD_ROWS[4:])
                     ).problems
    assert any("line 6, F: -2 N" in str(p) for p in problems)
