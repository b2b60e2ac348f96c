"""design fit on synthetic bench tests shaped like a camera session
(tests/fit_benches.py): fingers of known EI(s) under 0.5-8 N at 50, 75 and
100 % of their length, bent to tip slopes of 59-69 deg, four markers read
with 0.1 mm of noise.

Tolerances: the targets a smooth EI(s) (root-to-tip ratio up to 50) is
held to over the judged span (where the fit says EI is determined, less
10 % of the length at each end and half a marker spacing about a step):

* EI within 10 % of the truth;
* the 95 % band holds the truth at 90 % of the judged knots or more;
* the residuals at the noise: σ̂ (their RMS over the stated noise, per
  degree of freedom) within 3.5 of its standard deviations of 1, which for
  m readings is about 1/sqrt(2 m): a fit that explains the data fails this
  by chance less than once in 2000 runs;
* and the judged span at least half the finger, so that no test passes by
  determining nothing.

"Determined" is a band within ±10 %: the accuracy asked of the fit there.
With a wider band the fit can be off by more than 10 % while its band holds
the truth: at ±25 % some held-out fits were, where ln EI bends over a few
centimetres (a taper levelling off, a fall near the tip, a thickness
falling as (s/L)^0.7 to (s/L)^1.8). The tapers meet every target with x
and y readings, or y alone; x alone determines EI over half the finger on
a few of them only. On the other profiles (a thickness falling as
1 - k s², sigmoid falls, steps, inserts, a rib) the band is wider than
±10 % at most knots, little or nothing is claimed, and the tests ask that
what is claimed holds.

The default suite runs two fits through the command's run, computed ahead
by the prefetch worker (tests/prefetch.py): a moulded finger (taper-30) and
a strip thinning fastest at its clamp, whose GCV is least at the path's
first weight; ``-m slow`` runs the whole family with each kind of reading
(111 fits, about eight minutes), and benchmarks/fit_bench.py tabulates it
with times.
"""

from __future__ import annotations

import tempfile
from functools import lru_cache
from pathlib import Path

import numpy as np
import pytest

from design.io.scene import load_fit
from design.run.finger_fit import fit_finger, summarise
from design.run.fit import run
from tests import prefetch
from tests.fit_benches import FAMILY, READINGS, readings, score, write_problem


def noise_bound(m: int) -> float:
    """3.5 standard deviations of σ̂ for m readings (see the module docstring)."""
    return 3.5 / np.sqrt(2 * m)


def assert_recovered(name: str, knots, ei, low, high, determined, noise_scale, m: int):
    """The module docstring's targets for a smooth profile."""
    sc = score(name, np.asarray(knots), np.asarray(ei), np.asarray(low, float),
               np.asarray(high, float), np.asarray(determined))
    assert sc.span[1] - sc.span[0] >= 0.5 * FAMILY[name].length, sc
    assert sc.max_error <= 0.10, sc
    assert sc.coverage >= 0.9, sc
    assert abs(noise_scale - 1) <= noise_bound(m), noise_scale


#: the prefetch worker's key for :func:`moulded_fit` (tests/prefetch.py)
MOULDED = "tests/test_fit_bench.py: the moulded finger's fit"


def moulded_fit(folder: Path) -> tuple[bool, dict, str]:
    """A moulded finger (150 mm, EI falling 30x) read for x and y, written to
    ``folder`` and fitted through ``design fit``'s run (the command's exit
    status is its ``ok``): the result and the data file."""
    path = write_problem(folder, "taper-30")
    output = run(load_fit(path))
    return output.ok, output.result, path.with_suffix(".csv").read_text()


@pytest.fixture(scope="module")
def moulded_finger(tmp_path_factory):
    """:func:`moulded_fit`, run ahead by the prefetch worker into the folder
    it was given, or here."""
    folder = prefetch.folder(MOULDED, lambda: tmp_path_factory.mktemp("moulded"))
    return prefetch.result(MOULDED, moulded_fit, folder)


def test_the_moulded_finger_is_fitted_from_noisy_readings(moulded_finger):
    """Readings of markers near the root lie within noise of x = s, some past
    it: they are fitted as read, a warning counts their rows, and the fit
    meets the module docstring's targets with the x and the y readings each
    determining EI on their own; the model file predicts the readings within
    the noise of the fit's predictions."""
    ok, result, csv = moulded_finger
    assert ok and result["ok"] and result["method"] == "elastica"
    rows = [line.split(",") for line in csv.splitlines()[1:]]
    past = sum(np.hypot(float(x), float(y)) > float(s) or abs(float(x)) > float(s)
               for _, _, _, s, x, y in rows)
    assert past > 0                    # the bench does read markers past their bound
    assert result["warnings"][0].startswith(f"{past} row(s) read a point farther from the "
                                            f"clamp than its arc length s")
    p = result["profile"]
    assert_recovered("taper-30", p["s"], p["EI"], p["EI_low"], p["EI_high"], p["determined"],
                     result["noise_scale"], result["measurements"])
    by = result["determined_by"]
    assert by["x"] and by["y"]
    assert result["model"]["max_difference_from_fit_sigma"] < 1.0


#: the prefetch worker's key for :func:`clamp_taper_fit` (tests/prefetch.py)
CLAMP_TAPER = "tests/test_fit_bench.py: the fit of a finger thinning fastest at its clamp"


def clamp_taper_fit(folder: Path) -> dict:
    """``design fit``'s run on the x and y readings of a strip whose
    thickness falls as 1 - k (s/L)^0.7 (EI 25x from root to tip): the result."""
    return run(load_fit(write_problem(folder, "thickness-0.7-25"))).result


@pytest.fixture(scope="module")
def clamp_taper(tmp_path_factory):
    """:func:`clamp_taper_fit`, run ahead by the prefetch worker or here."""
    folder = prefetch.folder(CLAMP_TAPER, lambda: tmp_path_factory.mktemp("clamp_taper"))
    return prefetch.result(CLAMP_TAPER, clamp_taper_fit, folder)


def test_a_fit_at_the_path_s_first_weight_has_a_band_for_what_gcv_cannot_rule_out(clamp_taper):
    """EI falls fastest at the clamp, between the root and the first marker:
    an exponential profile explains the readings within their noise, GCV is
    least at the path's first weight, and that two-parameter fit is off by
    up to 10 % near the clamp while its own band is a few per cent wide. The
    band also covers the fits GCV cannot tell from it, so the module
    docstring's targets hold: EI within 10 % where determined and the band
    holding the truth at 90 % of those knots."""
    el, p = clamp_taper["elastica"], clamp_taper["profile"]
    assert el["chosen_solve"] == 0 and el["success"]
    assert el["band_also_covers_weight"] < el["weight"]
    assert_recovered("thickness-0.7-25", p["s"], p["EI"], p["EI_low"], p["EI_high"],
                     p["determined"], clamp_taper["noise_scale"], clamp_taper["measurements"])


@lru_cache(maxsize=None)
def bench_fit(name: str, which: str):
    """``design fit``'s fit of a bench (no files written but the problem's):
    the fit and its summary."""
    problem = load_fit(write_problem(Path(tempfile.mkdtemp()), name, which))
    ff = fit_finger(problem)
    return ff, summarise(problem, ff.fit)


#: the smooth benches whose x and y readings, or y readings alone, determine
#: EI over half the finger or more, and those of them where x readings alone
#: do (benchmarks/fit_bench.py: elsewhere the band is wider than ±10 % at
#: most knots, and nothing there is claimed)
DETERMINED = ("uniform", "taper-10", "thickness-20", "taper-30", "thickness-50", "thickness-30",
              "taper-50")
DETERMINED_BY_X = ("taper-30", "thickness-30")


@pytest.mark.slow
@pytest.mark.parametrize("which", list(READINGS))
@pytest.mark.parametrize("name", list(FAMILY))
def test_every_bench_fits_to_the_noise_and_claims_only_what_holds(name, which):
    """Every bench with each kind of reading: the fit converges, its
    residuals are at the noise, and wherever it calls EI determined (the
    judged span) EI is within 10 % and the band holds the truth at 90 % of
    the knots. x alone has no small-deflection fit (the refinement starts
    from the uniform elastica fit), and with one kind of reading the report
    says that kind determined EI."""
    ff, summary = bench_fit(name, which)
    data, _, _ = readings(name, which)
    assert ff.ok and ff.fit.method == "elastica"
    assert (ff.convex is None) == (which == "x")
    assert abs(ff.fit.selection.noise_scale - 1) <= noise_bound(len(data.observations))
    sc = score(name, summary.knots, summary.ei, summary.low, summary.high, summary.determined)
    assert sc.judged == 0 or (sc.max_error <= 0.10 and sc.coverage >= 0.9), sc
    if which != "x+y":
        assert list(summary.alone) == [which]
        assert np.array_equal(summary.alone[which], summary.determined)


@pytest.mark.slow
@pytest.mark.parametrize("name,which", [(n, w) for n in DETERMINED for w in ("x+y", "y")]
                         + [(n, "x") for n in DETERMINED_BY_X])
def test_tapers_are_recovered_over_most_of_the_finger(name, which):
    """The exponential and linear-thickness tapers (EI falling up to 50x)
    and the uniform finger: the module docstring's targets."""
    ff, summary = bench_fit(name, which)
    data, _, _ = readings(name, which)
    assert_recovered(name, summary.knots, summary.ei, summary.low, summary.high,
                     summary.determined, ff.fit.selection.noise_scale, len(data.observations))
