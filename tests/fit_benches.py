"""A family of synthetic bench tests of fingers, shaped like a camera session.

Each bench: a finger of known EI(s) under weights of 0.5, 1, 2, 4 and 8 N
hung perpendicular to it at 50, 75 and 100 % of its length; four markers at
25, 50, 75 and 100 % (or another number, evenly spaced to the tip) read for
x and y (or one of them) with Gaussian noise of 0.1 mm (numpy
default_rng, a seed per bench). The readings are the exact
elastica of the profile (the toolkit's collocation on 64 intervals, error
estimate below 1e-3 of the noise, asserted), so the model explains them.

The profiles (``FAMILY``) are smooth tapers, steps and inserts, each scaled
so that the heaviest load bends the finger's tip to 55-70 deg. ``TUNING``
are the ones the refinement was developed on; the others are held out, in
six batches (``SECOND_BATCH`` was added after the first batch had been
run, ``THIRD_BATCH`` after the second's, and so on): benchmarks/fit_bench.py
reports them apart.

:func:`score` judges a fit against the truth: the largest relative EI error
and the 95 % band's coverage over the *judged span*, the knots where the fit
says EI is determined (band within ±10 %) less the first and last 10 % of
the finger (at the clamp every reading integrates EI over a vanishing
stretch; at the tip no load acts past the last marker).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import casadi as ca
import numpy as np
import yaml

from design.calibration.data import FingerData, Observation
from design.calibration.elastica import elastica_predictions
from design.physics.beam import Finger, PointLoad
from design.physics.stiffness import ExponentialI, Stiffness

NOISE = 1e-4                                  # m, stated and simulated
FORCES = (0.5, 1.0, 2.0, 4.0, 8.0)            # N
LOAD_POINTS = (0.5, 0.75, 1.0)                # fractions of the length
MARKERS = 4                                   # evenly spaced, the last at the tip
#: the judged span leaves out this fraction of the length at each end
END_MARGIN = 0.1
READINGS = {"x+y": ("x", "y"), "x": ("x",), "y": ("y",)}


@dataclass(frozen=True, eq=False)
class LogProfile(Stiffness):
    """EI(s) = root exp(-rate s + Σ_k h_k (1 + tanh((s - at_k) / width_k)) / 2):
    an exponential taper (``rate``, 1/m) with smooth steps of ln-height h_k
    at at_k over ~width_k (m). ``steps``: ((h, at, width), ...)."""

    root: float
    rate: float = 0.0
    steps: tuple[tuple[float, float, float], ...] = ()

    def _log(self, s, exp, tanh):
        g = -self.rate * s
        for h, at, width in self.steps:
            g = g + h * (1 + tanh((s - at) / width)) / 2
        return self.root * exp(g)

    def ei(self, s):
        return self._log(np.asarray(s, dtype=float), np.exp, np.tanh)

    def dei(self, s):
        s = np.asarray(s, dtype=float)
        dg = -self.rate + sum(h / (2 * w * np.cosh((s - a) / w) ** 2) for h, a, w in self.steps)
        return self.ei(s) * dg

    @property
    def params(self):
        return np.array([self.root, self.rate, *np.ravel(self.steps)])

    def ei_casadi(self, s, p):
        g = -p[1] * s
        for k in range(len(self.steps)):
            h, at, width = p[2 + 3 * k], p[3 + 3 * k], p[4 + 3 * k]
            g = g + h * (1 + ca.tanh((s - at) / width)) / 2
        return p[0] * ca.exp(g)

    def symbolic_key(self):
        return (type(self).__name__, len(self.steps))

    def scaled(self, factor):
        return LogProfile(self.root * factor, self.rate, self.steps)

    def describe(self):
        return {"type": "log-profile", "root": self.root, "rate": self.rate,
                "steps": [list(s) for s in self.steps]}


@dataclass(frozen=True, eq=False)
class ThicknessTaper(Stiffness):
    """A strip whose thickness falls as 1 - k (s / length)^power:
    EI(s) = root (1 - k (s / length)^power)³, ``ratio`` = EI(0) / EI(length)
    = (1 - k)⁻³."""

    root: float
    ratio: float
    length: float
    power: float = 1.0

    @property
    def _k(self):
        return 1 - self.ratio ** (-1 / 3)

    def _t(self, s):
        return 1 - self._k * (np.asarray(s, dtype=float) / self.length) ** self.power

    def ei(self, s):
        return self.root * self._t(s) ** 3

    def dei(self, s):
        u = np.asarray(s, dtype=float) / self.length
        return -3 * self.root * self._t(s) ** 2 * self._k * self.power \
            * u ** (self.power - 1) / self.length

    @property
    def params(self):
        return np.array([self.root, self._k, self.length, self.power])

    def ei_casadi(self, s, p):
        return p[0] * (1 - p[1] * (s / p[2]) ** p[3]) ** 3

    def scaled(self, factor):
        return ThicknessTaper(self.root * factor, self.ratio, self.length, self.power)

    def describe(self):
        return {"type": "thickness-taper", "root": self.root, "ratio": self.ratio,
                "power": self.power}


@dataclass(frozen=True)
class Bench:
    """A finger (m, N m²) and the seed of its readings' noise."""

    name: str
    length: float
    stiffness: Stiffness
    seed: int
    what: str


def _thesis_shape(length: float, root: float) -> Stiffness:
    """The thesis's hard finger's EI(s) (eq. 2.33, rates 71 and 142 1/m over
    203 mm) stretched to ``length`` and scaled to EI(0) = ``root``."""
    A, B, C, a, b = 7.3e-8, -3.6551e-8, 3.2102e-9, -70.87, -141.73
    k = 0.203 / length
    return ExponentialI(root / (A + B + C), A, B, C, a * k, b * k)


FAMILY = {b.name: b for b in (
    Bench("uniform", 0.120, LogProfile(0.025), 11, "uniform"),
    Bench("taper-10", 0.150, LogProfile(0.116, np.log(10) / 0.150), 12,
          "exponential taper, EI(0)/EI(L) = 10"),
    Bench("step-4", 0.150, LogProfile(0.079, 0.0, ((-np.log(4), 0.075, 0.002),)), 13,
          "EI falls 4x over 4 mm at mid-length"),
    Bench("thickness-20", 0.120, ThicknessTaper(0.07, 20.0, 0.120), 14,
          "thickness falling linearly, EI(0)/EI(L) = 20"),
    Bench("insert-40", 0.120, LogProfile(0.085, 0.0, ((-np.log(6), 0.048, 0.003),)), 15,
          "a stiff insert over the first 40 %: EI 6x the rest's, ending over 6 mm"),
    Bench("taper-30", 0.150, LogProfile(0.18, np.log(30) / 0.150), 21,
          "exponential taper, EI(0)/EI(L) = 30 (a moulded finger)"),
    Bench("insert", 0.120, LogProfile(0.144, 0.0, ((-np.log(8), 0.040, 0.002),)), 22,
          "a stiff insert over the first third: EI 8x the rest's, ending over 4 mm"),
    Bench("thickness-50", 0.150, ThicknessTaper(0.16, 50.0, 0.150), 23,
          "thickness falling linearly, EI(0)/EI(L) = 50"),
    Bench("hinge", 0.150, LogProfile(0.058, 0.0, ((-np.log(3), 0.060, 0.006),
                                                 (np.log(3), 0.090, 0.006))), 24,
          "uniform with a soft stretch (EI / 3) from 60 to 90 mm"),
    Bench("thesis", 0.150, _thesis_shape(0.150, 0.3), 25,
          "the thesis's finger (eq. 2.33) on 150 mm, EI(0)/EI(L) = 12"),
    Bench("thickness-30", 0.150, ThicknessTaper(0.15, 30.0, 0.150), 41,
          "thickness falling linearly, EI(0)/EI(L) = 30"),
    Bench("taper-50", 0.160, LogProfile(0.30, np.log(50) / 0.160), 42,
          "exponential taper, EI(0)/EI(L) = 50"),
    Bench("parabolic-40", 0.140, ThicknessTaper(0.085, 40.0, 0.140, 2.0), 43,
          "thickness falling as 1 - k (s/L)², EI(0)/EI(L) = 40"),
    Bench("sigmoid-20", 0.130, LogProfile(0.13, 0.0, ((-np.log(20), 0.0715, 0.0156),)), 44,
          "EI falling 20x smoothly (tanh over ±16 mm) around 55 % of the length"),
    Bench("insert-half", 0.140, LogProfile(0.08, 0.0, ((-np.log(5), 0.070, 0.003),)), 45,
          "a stiff insert over the first half: EI 5x the rest's, ending over 6 mm"),
    Bench("rib", 0.140, LogProfile(0.033, 0.0, ((np.log(3), 0.056, 0.003),
                                               (-np.log(3), 0.091, 0.003))), 46,
          "uniform with a rib (EI x 3) from 56 to 91 mm"),
    Bench("sigmoid-wide-12", 0.140, LogProfile(0.115, 0.0, ((-np.log(12), 0.070, 0.035),)), 51,
          "EI falling 12x smoothly (tanh over ±35 mm) around mid-length"),
    Bench("thickness-cubic-35", 0.150, ThicknessTaper(0.071, 35.0, 0.150, 3.0), 52,
          "thickness falling as 1 - k (s/L)³, EI(0)/EI(L) = 35"),
    Bench("thickness-1.5-45", 0.130, ThicknessTaper(0.09, 45.0, 0.130, 1.5), 53,
          "thickness falling as 1 - k (s/L)^1.5, EI(0)/EI(L) = 45"),
    Bench("taper-flat-6", 0.150, LogProfile(0.107, np.log(20) / 0.150,
                                            ((0.4 * np.log(20), 0.090, 0.020),)), 54,
          "exponential taper levelling off (tanh over ±20 mm) at 90 mm, EI(0)/EI(L) = 6"),
    Bench("thickness-0.7-25", 0.140, ThicknessTaper(0.158, 25.0, 0.140, 0.7), 61,
          "thickness falling as 1 - k (s/L)^0.7, EI(0)/EI(L) = 25"),
    Bench("taper-sigmoid-24", 0.150, LogProfile(0.210, np.log(8) / 0.150,
                                                ((-np.log(3), 0.060, 0.035),)), 62,
          "exponential taper (8x) with a smooth 3x fall (tanh over ±35 mm) at 60 mm, "
          "EI(0)/EI(L) = 24"),
    Bench("thickness-2.5-15", 0.130, ThicknessTaper(0.051, 15.0, 0.130, 2.5), 63,
          "thickness falling as 1 - k (s/L)^2.5, EI(0)/EI(L) = 15"),
    Bench("droop-10", 0.140, LogProfile(0.074, 0.0, ((-np.log(10), 0.090, 0.030),)), 64,
          "EI falling 10x smoothly (tanh over ±30 mm) around 90 mm"),
    Bench("thickness-0.5-12", 0.130, ThicknessTaper(0.12, 12.0, 0.130, 0.5), 71,
          "thickness falling as 1 - k (s/L)^0.5, EI(0)/EI(L) = 12"),
    Bench("taper-double-18", 0.150, LogProfile(0.13, 0.0, ((-np.log(3), 0.050, 0.015),
                                                           (-np.log(6), 0.105, 0.015))), 72,
          "EI falling 3x (tanh over ±15 mm) at 50 mm and 6x more at 105 mm, EI(0)/EI(L) = 18"),
    Bench("thickness-1.2-35", 0.145, ThicknessTaper(0.12, 35.0, 0.145, 1.2), 73,
          "thickness falling as 1 - k (s/L)^1.2, EI(0)/EI(L) = 35"),
    Bench("taper-steepening-40", 0.150, LogProfile(0.17, np.log(5) / 0.150,
                                                   ((-np.log(8), 0.110, 0.025),)), 74,
          "exponential taper (5x) steepening (a further 8x, tanh over ±25 mm) at 110 mm, "
          "EI(0)/EI(L) = 40"),
    Bench("thickness-0.8-40", 0.135, ThicknessTaper(0.17, 40.0, 0.135, 0.8), 81,
          "thickness falling as 1 - k (s/L)^0.8, EI(0)/EI(L) = 40"),
    Bench("taper-bend-20", 0.140, LogProfile(0.22, np.log(4) / 0.140,
                                             ((-np.log(5), 0.040, 0.020),)), 82,
          "exponential taper (4x) with a smooth 5x fall (tanh over ±20 mm) at 40 mm, "
          "EI(0)/EI(L) = 20"),
    Bench("sigmoid-late-15", 0.130, LogProfile(0.07, 0.0, ((-np.log(15), 0.095, 0.020),)), 83,
          "EI falling 15x smoothly (tanh over ±20 mm) around 95 mm"),
    Bench("thickness-1.8-20", 0.150, ThicknessTaper(0.09, 20.0, 0.150, 1.8), 84,
          "thickness falling as 1 - k (s/L)^1.8, EI(0)/EI(L) = 20"),
    Bench("thickness-1.0-8", 0.110, ThicknessTaper(0.053, 8.0, 0.110), 91,
          "thickness falling linearly, EI(0)/EI(L) = 8"),
    Bench("taper-sigmoid-early-30", 0.150, LogProfile(0.32, np.log(10) / 0.150,
                                                      ((-np.log(3), 0.030, 0.015),)), 92,
          "exponential taper (10x) with a smooth 3x fall (tanh over ±15 mm) at 30 mm, "
          "EI(0)/EI(L) = 30"),
    Bench("thickness-0.6-50", 0.160, ThicknessTaper(0.34, 50.0, 0.160, 0.6), 93,
          "thickness falling as 1 - k (s/L)^0.6, EI(0)/EI(L) = 50"),
    Bench("soft-middle", 0.140, LogProfile(0.054, 0.0, ((-np.log(2), 0.045, 0.015),
                                                       (np.log(2), 0.095, 0.015))), 94,
          "uniform, EI halved smoothly (tanh over ±15 mm) from 45 to 95 mm"),
    Bench("step-3-late", 0.150, LogProfile(0.06, 0.0, ((-np.log(3), 0.100, 0.002),)), 95,
          "EI falls 3x over 4 mm at 100 mm"),
)}
#: the benches the method was developed on: its settings were chosen, and its
#: failures found and mended, on these; the others were run only once it was
#: settled, and are the evidence
TUNING = ("uniform", "taper-10", "step-4", "thickness-20", "insert-40", "taper-30", "insert",
          "thickness-50", "hinge", "thesis")
#: the second held-out batch: profiles added, and run once, after the first
#: held-out batch's results were known, with the method unchanged
SECOND_BATCH = ("sigmoid-wide-12", "thickness-cubic-35", "thickness-1.5-45", "taper-flat-6")
#: the third held-out batch: smooth profiles added, and run once, after the
#: second batch's results were known, with the method unchanged
THIRD_BATCH = ("thickness-0.7-25", "taper-sigmoid-24", "thickness-2.5-15", "droop-10")
#: the fourth held-out batch: profiles chosen (and scaled to their tip
#: slopes) before the band's rule for a fit at the path's first weight was
#: settled on the others, and run once with it
FOURTH_BATCH = ("thickness-0.5-12", "taper-double-18", "thickness-1.2-35", "taper-steepening-40")
#: the fifth held-out batch: profiles added, and run once, after the fourth
#: batch's results were known, with the method unchanged
FIFTH_BATCH = ("thickness-0.8-40", "taper-bend-20", "sigmoid-late-15", "thickness-1.8-20")
#: the sixth held-out batch: profiles chosen and scaled to their tip slopes
#: before EI was called determined only where its band is within ±10 %
#: (it had been ±25 %), and run once with that rule
SIXTH_BATCH = ("thickness-1.0-8", "taper-sigmoid-early-30", "thickness-0.6-50", "soft-middle",
               "step-3-late")
#: the benches with steps: judged no nearer a step than half the marker spacing
#: (the readings cannot place a step more closely; the roughness penalty
#: smooths it over that stretch)
STEPPED = ("step-4", "insert-40", "insert", "hinge", "insert-half", "rib", "step-3-late")


def loads(bench: Bench) -> tuple[PointLoad, ...]:
    return tuple(PointLoad(F, np.pi / 2, f * bench.length)
                 for f in LOAD_POINTS for F in FORCES)


def marker_fractions(markers: int = MARKERS) -> np.ndarray:
    """Where ``markers`` evenly spaced markers sit, as fractions of the length."""
    return np.arange(1, markers + 1) / markers


@lru_cache(maxsize=None)
def readings(name: str, which: str = "x+y", markers: int = MARKERS
             ) -> tuple[FingerData, np.ndarray, float]:
    """Noisy readings of a bench (``which``: a key of :data:`READINGS`) at
    ``markers`` markers, the exact values behind them, and the largest slope
    of any load case (rad)."""
    bench = FAMILY[name]
    cases = loads(bench)
    obs = tuple(Observation(k, f * bench.length, q, 0.0, NOISE, 0)
                for k in range(len(cases)) for f in marker_fractions(markers)
                for q in ("x", "y"))
    exact, sols = elastica_predictions(Finger(bench.length, bench.stiffness),
                                       FingerData(cases, obs), nodes=64)
    assert all(s.converged and s.error_estimate < 1e-3 * NOISE for s in sols)
    noisy = exact + NOISE * np.random.default_rng(bench.seed).standard_normal(exact.size)
    keep = [i for i, o in enumerate(obs) if o.quantity in READINGS[which]]
    data = FingerData(cases, tuple(Observation(o.case, o.s, o.quantity, noisy[i], o.sigma,
                                               2 + i // 2)
                                   for i, o in ((i, obs[i]) for i in keep)))
    slope = float(max(np.max(np.abs(s.psi)) for s in sols))
    return data, exact[keep], slope


def csv_text(name: str, which: str = "x+y", markers: int = MARKERS) -> str:
    """The bench's readings as a data file for ``design fit`` (mm, one row per
    marker and load)."""
    data, _, _ = readings(name, which, markers)
    rows: dict[int, dict] = {}
    for o in data.observations:
        rows.setdefault(o.line, {"case": o.case, "s": o.s})[o.quantity] = o.value
    cols = READINGS[which]
    out = ["F [N],alpha [deg],at [mm],s [mm]," + ",".join(f"{q} [mm]" for q in cols)]
    for line in sorted(rows):
        r = rows[line]
        ld = data.loads[r["case"]]
        out.append(f"{ld.force:g},90,{ld.at * 1e3:.6g},{r['s'] * 1e3:.6g},"
                   + ",".join(f"{r[q] * 1e3:.5f}" for q in cols))
    return "\n".join(out) + "\n"


def write_problem(folder: Path, name: str, which: str = "x+y", markers: int = MARKERS,
                  **fit) -> Path:
    """The bench's data file (``markers`` markers) and a fit problem for it
    (noise 0.1 mm, other ``fit`` settings as given) in ``folder``; the
    problem's path."""
    folder.mkdir(parents=True, exist_ok=True)
    stem = f"{name}_{which.replace('+', '')}" + (f"_{markers}" if markers != MARKERS else "")
    (folder / f"{stem}.csv").write_text(csv_text(name, which, markers))
    spec = {"kind": "fit", "target": "finger", "name": stem, "data": f"{stem}.csv",
            "finger": {"length": f"{FAMILY[name].length * 1e3:g} mm"},
            "fit": {"noise": {"position": "0.1 mm"}, **fit}}
    path = folder / f"{stem}.yaml"
    path.write_text(yaml.safe_dump(spec, sort_keys=False))
    return path


@dataclass(frozen=True)
class Score:
    """A fit against the truth over the judged span (see the module docstring)."""

    max_error: float          # largest |EI_fit / EI_true - 1|
    coverage: float           # fraction of judged knots whose 95 % band holds the truth
    judged: int               # knots judged
    span: tuple[float, float]  # first and last judged knot (m)


def judged_span(name: str, knots: np.ndarray, determined: np.ndarray,
                markers: int = MARKERS) -> np.ndarray:
    """The knots judged: determined, not within END_MARGIN of either end,
    and away from a step (half the spacing of ``markers`` markers)."""
    length = FAMILY[name].length
    mask = determined & (knots >= END_MARGIN * length - 1e-12) \
        & (knots <= (1 - END_MARGIN) * length + 1e-12)
    profile = FAMILY[name].stiffness
    if name in STEPPED:
        half_spacing = length / markers / 2
        for _, at, _ in profile.steps:
            mask &= np.abs(knots - at) >= half_spacing
    return mask


def score(name: str, knots: np.ndarray, ei: np.ndarray, low: np.ndarray, high: np.ndarray,
          determined: np.ndarray, markers: int = MARKERS) -> Score:
    """How far the fitted EI (N m² at ``knots``) is from the truth, and how
    often its band [low, high] holds it, over the judged span (NaN where no
    knot is judged)."""
    true = FAMILY[name].stiffness.ei(knots)
    mask = judged_span(name, knots, determined, markers)
    if not mask.any():
        return Score(np.nan, np.nan, 0, (np.nan, np.nan))
    err = np.abs(ei[mask] / true[mask] - 1)
    inside = (low[mask] <= true[mask]) & (true[mask] <= high[mask])
    return Score(float(err.max()), float(inside.mean()), int(mask.sum()),
                 (float(knots[mask][0]), float(knots[mask][-1])))
