"""Quantities with units in input files."""

import math

import pytest

from design.io.units import UnitError, to_si


@pytest.mark.parametrize("text, dimension, value", [
    ("4 in", "length", 0.1016), ("101.6 mm", "length", 0.1016), ("0.1016", "length", 0.1016),
    ("90 deg", "angle", math.pi / 2), ("90°", "angle", math.pi / 2), ("1.5 rad", "angle", 1.5),
    ("4.8 MPa", "modulus", 4.8e6), ("0.08 N m^2", "flexural_rigidity", 0.08),
    ("0.08 N*m**2", "flexural_rigidity", 0.08), ("0.08 N m²", "flexural_rigidity", 0.08),
    ("20 rpm", "angular_speed", 2 * math.pi / 3), ("18 in/s", "speed", 0.4572),
    ("1.8 kg", "mass", 1.8), ("0.00417 kg m^2", "inertia", 0.00417),
    ("7.3e-8 m^4", "area_moment", 7.3e-8), ("-70.87 1/m", "inverse_length", -70.87),
    ("5.6 ms", "time", 0.0056), ("2 lbf", "force", 8.896443230521),
])
def test_conversion_to_si(text, dimension, value):
    assert to_si(text, dimension) == pytest.approx(value, rel=1e-12)


@pytest.mark.parametrize("text, dimension, message", [
    ("4 inn", "length", "did you mean 'in'"),
    ("4 N", "length", "not a length"),
    ("abc", "length", "cannot read"),
    ("1 m/s/s", "acceleration", "more than one '/'"),
    (True, "length", "expected a number"),
    ("nan m", "length", "cannot read"),
    (float("inf"), "length", "not a finite number"),
    ([1], "length", "expected a number or a string"),
])
def test_malformed_quantities_are_refused(text, dimension, message):
    with pytest.raises(UnitError, match=message):
        to_si(text, dimension)
