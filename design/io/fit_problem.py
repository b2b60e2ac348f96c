"""Fit problems (``kind: fit``): calibrate a finger or a belt from measurements.

.. code-block:: yaml

    kind: fit
    target: finger                    # finger | belt
    data: bench_finger.csv            # a CSV beside this file (units in its header)
    finger: {length: 203 mm, E: 9.07 MPa}   # E optional: the model file then has E I(s)
    fit:                              # all optional
      knots: 31                       # compliance knots over [0, length]
      monotone: decreasing            # none | decreasing (EI never grows towards the tip) | increasing
      weight: gcv                     # gcv | l-curve: the rule that picks the smoothing weight
      method: auto                    # auto | small-deflection | elastica
      noise: {position: 0.5 mm, slope: 0.5 deg}   # the measurements' standard deviations
      model: table                    # table | exponential (the thesis's family, eq. 2.33)
      rates: {a: -70.87, b: -141.73}  # exponential only: its fixed rates (1/m)
    reference: models/fingers/thesis_nonuniform_hard.yaml   # optional: drawn beside the fit

    kind: fit
    target: belt
    data: belt_log.csv                # columns t and v
    belt: {time_zero: 1.4 s, knots: 29}   # the log's time at the simulation's t = 0; monotone fit's knots
    reference: {speed: 0.457, final_speed: 0.254, start_time: 0.4 s}   # optional: stated values

Finger data columns (a header row ``name [unit]``; lines starting with # are
comments; one row per measured point under one load):
``F`` load magnitude (≥ 0), ``alpha`` its direction (the toolkit's: the force
is F (-cos α, sin α) in the finger frame, 90 deg a push towards +y), ``at``
the load's arc length, ``s`` the measured point's arc length, and at least
one of ``x``, ``y`` (the point's position in the finger frame, y the
deflection) and ``psi`` (the finger's slope there). A reading is checked
against physics within its noise: a point lies within its arc length s of
the clamp and a slope within half a turn, and a reading past that bound by
more than :data:`BOUND_SIGMAS` standard deviations of the stated noise is
refused; nearer, it is noise on a true value within the bound, fitted as
read, and a warning counts such rows. Belt columns: ``t`` (strictly
increasing) and ``v`` (≥ 0).
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from design.calibration.data import FingerData, Observation
from design.io.fingers import read_finger
from design.io.files import resolve, searched
from design.io.reader import Reader, interval
from design.io.units import SI_NAMES, UnitError, to_si
from design.physics.beam import Finger, PointLoad

TARGETS = ("finger", "belt")
MONOTONE = ("none", "decreasing", "increasing")
METHODS = ("auto", "small-deflection", "elastica")
MODELS = ("table", "exponential")
WEIGHTS = ("gcv", "l-curve")
#: the thesis's exponential rates (eq. 2.33), the default for model: exponential
THESIS_RATES = (-70.87, -141.73)
#: finger CSV columns: name -> (dimension, required)
FINGER_COLUMNS = {"F": ("force", True), "alpha": ("angle", True), "at": ("length", True),
                  "s": ("length", True), "x": ("length", False), "y": ("length", False),
                  "psi": ("angle", False)}
BELT_COLUMNS = {"t": ("time", True), "v": ("speed", True)}
#: fewest measured values a finger fit takes (a profile and the noise
#: behind it cannot come from fewer)
MIN_FINGER_VALUES = 6
#: a reading may pass its physical bound (|x| ≤ s, ...) by this many standard
#: deviations of its stated noise and still be a reading of a true value
#: within it: the chance of Gaussian noise reaching 5 σ is 3e-7 per reading
BOUND_SIGMAS = 5.0
#: fewest samples a belt fit takes (four parameters and the noise)
MIN_BELT_SAMPLES = 8


@dataclass(frozen=True)
class FingerFitSettings:
    """How a finger is fitted (see the module docstring for each key)."""

    knots: int = 31
    #: None, "decreasing" or "increasing": how EI(s) may vary from base to tip
    monotone: str | None = None
    weight: str = "gcv"
    method: str = "auto"
    #: stated standard deviations of a measured position (m) and slope (rad)
    noise_position: float = 0.5e-3
    noise_slope: float = math.radians(0.5)
    model: str = "table"
    #: the exponential family's rates a, b (1/m)
    rates: tuple[float, float] = THESIS_RATES


@dataclass(frozen=True)
class FingerFitProblem:
    """A finger to calibrate: its length (m), modulus E (Pa, None: unknown),
    the measurements, the settings and an optional reference finger."""

    name: str
    data_file: Path
    data: FingerData
    length: float
    E: float | None
    settings: FingerFitSettings
    reference: Finger | None = None
    description: str = ""


@dataclass(frozen=True)
class BeltFitProblem:
    """An encoder log to fit: times (s) and belt speeds (m/s), the log's time
    at the simulation's t = 0 (s), the monotone fit's knot count, and the
    stated values to compare with (SI, any of speed, final_speed,
    start_time, rate)."""

    name: str
    data_file: Path
    t: np.ndarray
    v: np.ndarray
    time_zero: float
    knots: int
    reference: dict
    description: str = ""


def read_fit(reader: Reader, data: dict, base_dir: Path, name: str
             ) -> FingerFitProblem | BeltFitProblem | None:
    """A fit problem from its parsed YAML (``kind: fit``), its data file read
    and checked row by row (problems there name the data file and line)."""
    common = ("kind", "target", "data", "name", "description", "reference")
    target = reader.choice(data, "target", "", TARGETS)
    extra = {"finger": ("finger", "fit"), "belt": ("belt",)}.get(target, ())
    required = ("finger",) if target == "finger" else ()
    reader.mapping(data, "", required=("kind", "target", "data", *required),
                   optional=(*common, *extra))
    name = reader.text(data, "name", "", default=name)
    description = reader.text(data, "description", "", default="")
    path = _data_file(reader, data, base_dir)
    if target == "finger":
        return _finger_fit(reader, data, base_dir, name, description, path)
    if target == "belt":
        return _belt_fit(reader, data, name, description, path)
    return None


def _data_file(reader: Reader, data: dict, base_dir: Path) -> Path | None:
    value = data.get("data")
    if value is None:
        return None
    if not isinstance(value, str):
        reader.add("data", f"expected the path of a CSV file, got {value!r}")
        return None
    path = resolve(value, base_dir)
    if path is None:
        reader.add("data", f"data file '{value}' not found (looked in {searched(base_dir)})")
    return path


def _finger_fit(reader: Reader, data: dict, base_dir: Path, name: str, description: str,
                path: Path | None) -> FingerFitProblem | None:
    spec = reader.mapping(data.get("finger"), "finger", required=("length",),
                          optional=("E",)) if "finger" in data else None
    length = reader.quantity(spec, "length", "finger", "length", lo=0.0, lo_open=True) \
        if spec is not None else None
    E = reader.quantity(spec, "E", "finger", "modulus", lo=0.0, lo_open=True, default=None) \
        if spec is not None else None
    settings = _finger_settings(reader, data.get("fit", {}))
    reference = read_finger(reader, data["reference"], "reference", base_dir) \
        if "reference" in data else None
    measured = None
    if path is not None and length is not None:
        measured = read_finger_data(reader, path, length, settings or FingerFitSettings())
    if measured is not None and settings is not None and settings.method == "small-deflection" \
            and all(o.quantity == "x" for o in measured.observations):
        reader.add("fit.method", f"small-deflection fits y and psi readings, and {path.name} has "
                                 f"only x (to first order a point moves across the finger, not "
                                 f"along it): use auto or elastica")
    if not reader.ok or None in (name, description, length, settings, measured):
        return None
    return FingerFitProblem(name, path, measured, length, E, settings, reference, description)


def _finger_settings(reader: Reader, value: object) -> FingerFitSettings | None:
    spec = reader.mapping(value, "fit", optional=("knots", "monotone", "weight", "method",
                                                  "noise", "model", "rates"))
    if spec is None:
        return None
    d = FingerFitSettings()
    knots = reader.integer(spec, "knots", "fit", lo=5, hi=201, default=d.knots)
    monotone = reader.choice(spec, "monotone", "fit", MONOTONE, default="none")
    weight = reader.choice(spec, "weight", "fit", WEIGHTS, default=d.weight)
    method = reader.choice(spec, "method", "fit", METHODS, default=d.method)
    model = reader.choice(spec, "model", "fit", MODELS, default=d.model)
    noise = reader.mapping(spec.get("noise", {}), "fit.noise", optional=("position", "slope"))
    pos = reader.quantity(noise or {}, "position", "fit.noise", "length", lo=0.0, lo_open=True,
                          default=d.noise_position)
    slope = reader.quantity(noise or {}, "slope", "fit.noise", "angle", lo=0.0, lo_open=True,
                            default=d.noise_slope)
    rates = d.rates
    if "rates" in spec:
        if model != "exponential":
            reader.add("fit.rates", "only the exponential model has rates")
        r = reader.mapping(spec["rates"], "fit.rates", required=("a", "b"))
        if r is not None:
            a = reader.quantity(r, "a", "fit.rates", "inverse_length")
            b = reader.quantity(r, "b", "fit.rates", "inverse_length")
            if a is not None and b is not None and a == b:
                reader.add("fit.rates", "a and b must differ (the family's two exponentials)")
            rates = (a, b)
    if None in (knots, monotone, weight, method, model, noise, pos, slope, *rates):
        return None
    return FingerFitSettings(knots, None if monotone == "none" else monotone, weight, method,
                             pos, slope, model, rates)


def _belt_fit(reader: Reader, data: dict, name: str, description: str, path: Path | None
              ) -> BeltFitProblem | None:
    spec = reader.mapping(data.get("belt", {}), "belt", optional=("time_zero", "knots"))
    t0 = reader.quantity(spec or {}, "time_zero", "belt", "time", default=None)
    knots = reader.integer(spec or {}, "knots", "belt", lo=3, hi=1000, default=None)
    ref = {}
    if "reference" in data:
        rs = reader.mapping(data["reference"], "reference",
                            optional=("speed", "final_speed", "start_time", "rate"))
        dims = {"speed": "speed", "final_speed": "speed", "start_time": "time",
                "rate": "acceleration"}
        for key in rs or {}:
            if key in dims:
                ref[key] = reader.quantity(rs, key, "reference", dims[key], lo=0.0)
    table = read_table(reader, path, BELT_COLUMNS) if path is not None else None
    if table is None or not reader.ok:
        return None
    sub = Reader(str(path))
    t, v = np.array(table["t"]), np.array(table["v"])
    lines = table["_line"]
    for i, (vi, line) in enumerate(zip(v, lines)):
        if vi < 0:
            sub.add(f"line {line}, v", f"{vi:g} m/s is outside the accepted range "
                                       f"{interval(0, None, False, False)} m/s")
    for i in np.flatnonzero(np.diff(t) <= 0)[:5]:
        sub.add(f"line {lines[i + 1]}, t", f"{t[i + 1]:g} s does not come after the previous "
                                           f"row's {t[i]:g} s: times must strictly increase")
    if t.size < MIN_BELT_SAMPLES:
        sub.add("", f"too few samples: {t.size}; a belt fit needs at least {MIN_BELT_SAMPLES}")
    if knots is not None and knots > t.size:
        reader.add("belt.knots", f"{knots} knots for {t.size} samples: at most one per sample")
    if t0 is not None and t.size and not (t[0] - 1e-12 <= t0 <= t[-1]):
        reader.add("belt.time_zero", f"{t0:g} s is outside the log, accepted range "
                                     f"{interval(t[0], t[-1], False, False)} s")
    for problem in sub.problems:
        reader.record(problem)
    if not reader.ok:
        return None
    knots = knots or min(max(t.size // 5, 3), 60)
    return BeltFitProblem(name, path, t, v, float(t[0]) if t0 is None else t0, knots, ref,
                          description)


def read_finger_data(reader: Reader, path: Path, length: float,
                     settings: FingerFitSettings) -> FingerData | None:
    """The finger CSV as load cases and observations, every row checked;
    problems are recorded in ``reader`` under the CSV's name and line."""
    table = read_table(reader, path, FINGER_COLUMNS)
    if table is None:
        return None
    sub = Reader(str(path))
    rows = list(zip(*(table[k] for k in ("F", "alpha", "at", "s", "x", "y", "psi", "_line"))))
    cases: dict[tuple, int] = {}
    obs = []
    beyond: list[tuple[int, float]] = []      # (line, excess in σ) within the bound's allowance
    for F, alpha, at, s, x, y, psi, line in rows:
        where = f"line {line}"
        ok = True
        for key, value, lo, hi, lo_open, unit in (
                ("F", F, 0.0, None, False, "N"), ("alpha", alpha, -np.pi, np.pi, False, "rad"),
                ("at", at, 0.0, length, True, "m"), ("s", s, 0.0, length, True, "m")):
            if (value < lo or (lo_open and value == lo)) or (hi is not None and value > hi):
                sub.add(f"{where}, {key}", f"{value:g} {unit} is outside the accepted range "
                                           f"{interval(lo, hi, lo_open, False)} {unit}"
                                           + (f" (the finger is {length:g} m long)"
                                              if key in ("at", "s") else ""))
                ok = False
        if x is None and y is None and psi is None:
            sub.add(where, "no measured value: give x, y or psi")
            ok = False
        for bound in physical_bounds(s, x, y, psi, settings):
            if bound.excess > BOUND_SIGMAS * bound.sigma:
                sub.add(f"{where}, {bound.column}", bound.refusal())
                ok = False
            elif bound.excess > 0:
                beyond.append((line, bound.excess / bound.sigma))
        if not ok:
            continue
        k = cases.setdefault((F, alpha, at), len(cases))
        for quantity, value in (("x", x), ("y", y), ("psi", psi)):
            if value is not None:
                sigma = settings.noise_slope if quantity == "psi" else settings.noise_position
                obs.append(Observation(k, s, quantity, value, sigma, line))
    if sub.ok and len(obs) < MIN_FINGER_VALUES:
        sub.add("", f"too few points: {len(obs)} measured values (x, y or psi); a finger fit "
                    f"needs at least {MIN_FINGER_VALUES}")
    if sub.ok and all(F * abs(math.sin(alpha)) == 0 for F, alpha, _ in cases):
        sub.add("F", "every load is zero or along the finger: nothing bends it")
    for problem in sub.problems:
        reader.record(problem)
    if not sub.ok:
        return None
    loads = tuple(PointLoad(F, alpha, at) for F, alpha, at in cases)
    return FingerData(loads, tuple(obs), beyond_bound_note(beyond))


@dataclass(frozen=True)
class Bound:
    """A reading against its physical bound: ``shown`` (the reading as the
    message gives it) is ``excess`` past ``bound`` (m or rad), the largest
    value its true value can have (``what``); ``sigma`` is the stated noise,
    set by ``noise_key``."""

    column: str
    shown: str
    bound: float
    excess: float
    sigma: float
    what: str
    noise_key: str

    def refusal(self) -> str:
        unit = "rad" if self.column == "psi" else "m"
        limit = self.bound + BOUND_SIGMAS * self.sigma
        return (f"{self.shown} {unit} is more than {self.what} {self.bound:g} {unit} by "
                f"{self.excess / self.sigma:.3g} standard deviations of the stated noise "
                f"({self.noise_key} = {self.sigma:g} {unit}): accepted range "
                f"{interval(-limit, limit, False, False)} {unit} (the bound widened by "
                f"{BOUND_SIGMAS:g} standard deviations)")


def physical_bounds(s: float, x: float | None, y: float | None, psi: float | None,
                    settings: FingerFitSettings) -> list[Bound]:
    """Each reading of one row against what its true value cannot exceed: a
    point at arc length s lies within s of the clamp (|x|, |y| and
    sqrt(x² + y²) at most s), a slope within half a turn (|ψ| ≤ π)."""
    pos, slope = settings.noise_position, settings.noise_slope
    out = [Bound(key, f"|{value:g}|", s, abs(value) - s, pos, "the point's arc length s =",
                 "fit.noise.position")
           for key, value in (("x", x), ("y", y)) if value is not None]
    if x is not None and y is not None:
        r = math.hypot(x, y)
        out.append(Bound("x, y", f"the distance from the clamp sqrt(x² + y²) = {r:g}", s, r - s,
                         pos, "the point's arc length s =", "fit.noise.position"))
    if psi is not None:
        out.append(Bound("psi", f"|{psi:g}|", np.pi, abs(psi) - np.pi, slope, "half a turn,",
                         "fit.noise.slope"))
    return out


def beyond_bound_note(beyond: list[tuple[int, float]]) -> str | None:
    """The warning that counts the rows with readings past their physical
    bound by no more than :data:`BOUND_SIGMAS` standard deviations: taken as
    noise, they are fitted as read. ``beyond``: (line, excess in σ) of each."""
    if not beyond:
        return None
    lines = sorted({line for line, _ in beyond})
    shown = ", ".join(str(v) for v in lines[:20]) + (", ..." if len(lines) > 20 else "")
    return (f"{len(lines)} row(s) read a point farther from the clamp than its arc length s, "
            f"or a slope past ±180 deg, by up to {max(e for _, e in beyond):.2g} standard "
            f"deviations of the stated noise (at most {BOUND_SIGMAS:g} accepted): taken as "
            f"noise and fitted as read (lines {shown})")


def read_table(reader: Reader, path: Path, columns: dict[str, tuple[str, bool]]
               ) -> dict[str, list] | None:
    """A CSV with a ``name [unit]`` header (``#`` lines are comments) as
    columns in SI, None in an empty cell; ``_line`` holds each row's line
    number. Problems are recorded under the CSV's name."""
    sub = Reader(str(path))
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        reader.add("data", f"cannot read '{path}' as a UTF-8 text file: "
                           f"{getattr(exc, 'strerror', None) or exc}")
        return None
    numbered = [(i + 1, line) for i, line in enumerate(text.splitlines())
                if line.strip() and not line.lstrip().startswith("#")]
    if not numbered:
        sub.add("", "no header and no rows (only comments or nothing)")
        reader.record(sub.problems[0])
        return None
    head_line, head = numbered[0]
    cells = next(csv.reader([head]))
    order, factors = [], []
    for cell in cells:
        name, unit = _header_cell(cell)
        where = f"line {head_line}, column '{cell.strip()}'"
        if name not in columns:
            sub.add(where, f"unknown column (allowed: {', '.join(columns)})")
            order.append(None)
            factors.append(None)
            continue
        dim = columns[name][0]
        if not unit:
            sub.add(where, f"no unit: write it in brackets, e.g. '{name} "
                           f"[{SI_NAMES[dim] or '1'}]'")
            factor = None
        else:
            try:
                factor = to_si(f"1 {unit}", dim)
            except UnitError as exc:
                sub.add(where, f"{exc}; this column is a {dim.replace('_', ' ')} "
                               f"({SI_NAMES[dim] or 'dimensionless'} or a unit of the same kind)")
                factor = None
        if name in order:
            sub.add(where, "the column appears twice")
        order.append(name)
        factors.append(factor)
    for name, (_, required) in columns.items():
        if required and name not in order:
            sub.add(f"line {head_line}", f"missing column '{name}' (required: "
                                         f"{', '.join(k for k, (_, r) in columns.items() if r)})")
    if not sub.ok:
        for problem in sub.problems:
            reader.record(problem)
        return None
    out: dict[str, list] = {name: [] for name in columns}
    out["_line"] = []
    for line_no, line in numbered[1:]:
        row = next(csv.reader([line]))
        if len(row) != len(order):
            sub.add(f"line {line_no}", f"{len(row)} cells where the header has {len(order)}")
            continue
        values = {}
        for name, factor, cell in zip(order, factors, row):
            cell = cell.strip()
            if not cell:
                if columns[name][1]:
                    sub.add(f"line {line_no}, {name}", "empty; this column is required")
                values[name] = None
                continue
            try:
                value = float(cell)
            except ValueError:
                value = math.nan
            if not math.isfinite(value):
                sub.add(f"line {line_no}, {name}", f"'{cell}' is not a finite number (the "
                                                   f"column's unit is in its header)")
                continue
            values[name] = value * factor
        for name in columns:
            out[name].append(values.get(name))
        out["_line"].append(line_no)
    if sub.ok and not out["_line"]:
        sub.add("", "a header but no rows")
    for problem in sub.problems:
        reader.record(problem)
    return out if sub.ok else None


def _header_cell(cell: str) -> tuple[str, str]:
    """'F [N]' -> ('F', 'N'); 'F' -> ('F', '')."""
    text = cell.strip()
    if text.endswith("]") and "[" in text:
        name, unit = text[:-1].split("[", 1)
        return name.strip(), unit.strip()
    return text, ""
