"""Quantities with units in input files, converted to SI.

A number without a unit is taken as SI (radians for angles). A string such as
``"90 deg"``, ``"4 in"``, ``"4.8 MPa"``, ``"0.08 N m^2"`` or ``"20 rpm"`` is
parsed and converted; its dimension must match the field's.

Hand-written rather than ``pint``: the toolkit needs a few dozen units, a
dimension check and messages that name the field, and a registry would add
start-up time to every command for no gain.
"""

from __future__ import annotations

import difflib
import math
import re

# Dimension exponents over (metre, kilogram, second). Angles are dimensionless.
Dim = tuple[int, int, int]

DIMENSIONS: dict[str, Dim] = {
    "dimensionless": (0, 0, 0),
    "angle": (0, 0, 0),
    "length": (1, 0, 0),
    "inverse_length": (-1, 0, 0),
    "area_moment": (4, 0, 0),
    "mass": (0, 1, 0),
    "time": (0, 0, 1),
    "force": (1, 1, -2),
    "modulus": (-1, 1, -2),
    "flexural_rigidity": (3, 1, -2),
    "inertia": (2, 1, 0),
    "speed": (1, 0, -1),
    "acceleration": (1, 0, -2),
    "jerk": (1, 0, -3),
    "angular_speed": (0, 0, -1),
    "spring_stiffness": (0, 1, -2),
    "damping": (0, 1, -1),
}

SI_NAMES: dict[str, str] = {
    "dimensionless": "", "angle": "rad", "length": "m", "inverse_length": "1/m",
    "area_moment": "m^4", "mass": "kg", "time": "s", "force": "N", "modulus": "Pa",
    "flexural_rigidity": "N m^2", "inertia": "kg m^2", "speed": "m/s",
    "acceleration": "m/s^2", "jerk": "m/s^3", "angular_speed": "rad/s",
    "spring_stiffness": "N/m", "damping": "N s/m",
}

_N: Dim = (1, 1, -2)
_PA: Dim = (-1, 1, -2)
# name -> (factor to SI, dimension)
UNITS: dict[str, tuple[float, Dim]] = {
    "1": (1.0, (0, 0, 0)),
    "m": (1.0, (1, 0, 0)), "mm": (1e-3, (1, 0, 0)), "cm": (1e-2, (1, 0, 0)),
    "um": (1e-6, (1, 0, 0)), "µm": (1e-6, (1, 0, 0)), "km": (1e3, (1, 0, 0)),
    "in": (0.0254, (1, 0, 0)), "inch": (0.0254, (1, 0, 0)), "inches": (0.0254, (1, 0, 0)),
    "ft": (0.3048, (1, 0, 0)),
    "kg": (1.0, (0, 1, 0)), "g": (1e-3, (0, 1, 0)), "lb": (0.45359237, (0, 1, 0)),
    "s": (1.0, (0, 0, 1)), "ms": (1e-3, (0, 0, 1)), "min": (60.0, (0, 0, 1)),
    "N": (1.0, _N), "kN": (1e3, _N), "mN": (1e-3, _N), "lbf": (4.4482216152605, _N),
    "Pa": (1.0, _PA), "kPa": (1e3, _PA), "MPa": (1e6, _PA), "GPa": (1e9, _PA),
    "psi": (6894.757293168, _PA),
    "rad": (1.0, (0, 0, 0)), "deg": (math.pi / 180, (0, 0, 0)),
    "degree": (math.pi / 180, (0, 0, 0)), "degrees": (math.pi / 180, (0, 0, 0)),
    "°": (math.pi / 180, (0, 0, 0)), "rev": (2 * math.pi, (0, 0, 0)),
    "rpm": (2 * math.pi / 60, (0, 0, -1)), "Hz": (1.0, (0, 0, -1)),
}

_NUMBER = re.compile(r"^\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*(.*?)\s*$")
_TERM = re.compile(r"^([^\s*/^·]+?)(?:(?:\^|\*\*)([-+]?\d+)|([²³⁴]))?$")
_SUPERSCRIPT = {"²": 2, "³": 3, "⁴": 4}


class UnitError(ValueError):
    """A quantity string that cannot be read or has the wrong dimension."""


def _unit_factor(expr: str, dimension: str) -> tuple[float, Dim]:
    """Factor to SI and dimension of a unit expression like ``N m^2`` or ``m/s^2``."""
    factor, dim = 1.0, [0, 0, 0]
    sign = 1
    tokens = re.findall(r"/|[^\s*/·]+", expr.replace("**", "^"))
    if not tokens:
        raise UnitError("no unit")
    for tok in tokens:
        if tok == "/":
            if sign < 0:
                raise UnitError(f"more than one '/' in unit '{expr}'")
            sign = -1
            continue
        m = _TERM.match(tok)
        if not m or m.group(1) not in UNITS:
            raise UnitError(f"unknown unit '{tok}'{_hint(tok, dimension)}")
        power = int(m.group(2)) if m.group(2) else _SUPERSCRIPT.get(m.group(3), 1)
        f, d = UNITS[m.group(1)]
        factor *= f ** (sign * power)
        for i in range(3):
            dim[i] += sign * power * d[i]
    return factor, (dim[0], dim[1], dim[2])


def _hint(token: str, dimension: str) -> str:
    """Close matches among the units of the expected dimension."""
    same = [k for k, (_, d) in UNITS.items() if d == DIMENSIONS[dimension] and k != "1"]
    close = difflib.get_close_matches(token, list(UNITS), n=1)
    parts = []
    if close:
        parts.append(f"did you mean '{close[0]}'?")
    if same and len(same) < 12:
        parts.append(f"{dimension.replace('_', ' ')} units: {', '.join(same)}")
    return " (" + "; ".join(parts) + ")" if parts else ""


def to_si(value: object, dimension: str) -> float:
    """Convert a number or a ``"<number> <unit>"`` string to SI.

    Parameters
    ----------
    value : int, float or str
        A bare number is already SI; a string carries its unit.
    dimension : str
        One of :data:`DIMENSIONS`; the unit must have this dimension.

    Returns
    -------
    float
        The value in SI units (radians for angles, rad/s for rpm).

    Raises
    ------
    UnitError
        Malformed string, unknown unit, or wrong dimension.

    Examples
    --------
    >>> round(to_si("4 in", "length"), 4)
    0.1016
    >>> to_si("4.8 MPa", "modulus")
    4800000.0
    """
    if isinstance(value, bool):
        raise UnitError(f"expected a number, got {value!r}")
    if isinstance(value, (int, float)):
        out = float(value)
    elif isinstance(value, str):
        m = _NUMBER.match(value)
        if not m:
            raise UnitError(f"cannot read '{value}' as '<number> <unit>'")
        number, unit = float(m.group(1)), m.group(2)
        if not unit:
            out = number
        else:
            factor, dim = _unit_factor(unit, dimension)
            expected = DIMENSIONS[dimension]
            if dim != expected:
                raise UnitError(
                    f"unit '{unit}' is not a {dimension.replace('_', ' ')} "
                    f"(expected something like '{SI_NAMES[dimension] or 'a plain number'}')")
            out = number * factor
    else:
        raise UnitError(f"expected a number or a string with a unit, got {type(value).__name__}")
    if not math.isfinite(out):
        raise UnitError(f"not a finite number: {value!r}")
    return out
