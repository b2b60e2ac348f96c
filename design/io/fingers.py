"""Reading a finger (inline or from ``models/fingers/*.yaml``) into a :class:`Finger`.

A finger is ``{length, EI}`` for a uniform finger, or ``{length, E, I}`` with
``I`` one of::

    {type: uniform, value: 1.67e-8}                         # m^4
    {type: exponential, A: .., B: .., C: .., a: .., b: ..}  # I = A e^(a s) + B e^(b s) + C
    {type: table, s: [...], I: [...]}                       # cubic spline, s from 0 to length

The spatial finger model (a rod that also bends towards z and twists) needs
the section's other two rigidities; a round section's are the default
(EI_out = EI, GJ = EI / (1 + ν), ν = 0.5 for rubber). Give them as
``EI_out``/``GJ`` (N m², uniform) beside ``EI``, or as ``I_out`` (m⁴, the
second moment about the section's long axis) and ``J`` (m⁴, the torsion
constant) beside ``E`` and ``I``, in any of the ``I`` forms, with
``poisson`` (ν, default 0.5) for G = E / (2 (1 + ν)).

A finger file may also carry ``kind: finger``, ``name``, ``description`` and
``source``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from design.io.files import read_model
from design.io.reader import Reader, join
from design.physics.beam import Finger
from design.physics.rod import RUBBER_POISSON
from design.physics.stiffness import ExponentialI, Stiffness, TableI, UniformEI

I_TYPES = ("uniform", "exponential", "table")
_FINGER_KEYS = ("length", "EI", "E", "I", "EI_out", "GJ", "I_out", "J", "poisson", "name",
                "description", "source", "kind")


def read_finger(reader: Reader, value: object, field: str, base_dir: Path) -> Finger | None:
    """A finger given inline (mapping) or as a path to a finger file."""
    return read_model(reader, value, field, base_dir, "finger", _finger)


def _finger(reader: Reader, value: object, field: str, base_dir: Path,
            default_name: str) -> Finger | None:
    data = reader.mapping(value, field, required=("length",), optional=_FINGER_KEYS[1:])
    if data is None:
        return None
    if "kind" in data and data["kind"] != "finger":
        reader.add(join(field, "kind"), f"'{data['kind']}' in a finger; expected 'finger'")
    length = reader.quantity(data, "length", field, "length", lo=0.0, lo_open=True)
    name = reader.text(data, "name", field, default=default_name)
    reader.text(data, "description", field, default="")
    reader.text(data, "source", field, default="")
    stiffness = read_stiffness(reader, data, field)
    stiff, torsion = _section_rigidities(reader, data, field, stiffness)
    for key, profile in (("I", stiffness), ("I_out", stiff), ("J", torsion)):
        if isinstance(profile, TableI) and length is not None and \
                profile.s_knots[-1] < length:
            reader.add(join(field, f"{key}.s"), f"the table ends at s = "
                                                f"{profile.s_knots[-1]:g} m, before the "
                                                f"finger's end ({length:g} m); it must cover "
                                                f"[0, length]")
        elif profile is not None and length is not None:
            _check_positive(reader, profile, length, field, key)
    if stiffness is None or length is None or name is None or not reader.ok:
        return None
    return Finger(length, stiffness, name, stiff, torsion)


def _section_rigidities(reader: Reader, data: dict, field: str, stiffness: Stiffness | None
                        ) -> tuple[Stiffness | None, Stiffness | None]:
    """(EI_out, GJ) profiles, each None when not given (the round default).
    ``stiffness`` is the finger's EI(s) (None when it had problems)."""
    if "EI" in data:
        for key in ("I_out", "J", "poisson"):
            if key in data:
                reader.add(join(field, key), "goes with E and I; with EI give EI_out and GJ")
        out = [reader.quantity(data, key, field, "flexural_rigidity", lo=0.0, lo_open=True,
                               default=None) for key in ("EI_out", "GJ")]
        return tuple(None if v is None else UniformEI(v) for v in out)
    for key in ("EI_out", "GJ"):
        if key in data:
            reader.add(join(field, key), "goes with EI; with E and I give I_out and J")
    nu = reader.quantity(data, "poisson", field, "dimensionless", lo=0.0, hi=0.5,
                         default=RUBBER_POISSON)
    if stiffness is None or nu is None:     # E and I had problems, reported already
        return None, None
    E = reader.quantity(data, "E", field, "modulus", lo=0.0, lo_open=True)
    stiff = _profile(reader, data["I_out"], join(field, "I_out"), E) if "I_out" in data else None
    shear = E / (2 * (1 + nu))
    torsion = _profile(reader, data["J"], join(field, "J"), shear) if "J" in data else None
    return stiff, torsion


def read_stiffness(reader: Reader, data: dict, field: str) -> Stiffness | None:
    """EI, or E with an I profile, from a finger mapping."""
    has_ei, has_e, has_i = "EI" in data, "E" in data, "I" in data
    if has_ei and (has_e or has_i):
        reader.add(join(field, "EI"), "give either EI, or E with I, not both")
        return None
    if has_ei:
        ei = reader.quantity(data, "EI", field, "flexural_rigidity", lo=0.0, lo_open=True)
        return None if ei is None else UniformEI(ei)
    if not (has_e and has_i):
        missing = "E" if has_i else "I" if has_e else "EI (or E with I)"
        reader.add(join(field, missing.split()[0]), f"required but missing: {missing}")
        return None
    E = reader.quantity(data, "E", field, "modulus", lo=0.0, lo_open=True)
    if E is None:
        return None
    return _profile(reader, data["I"], join(field, "I"), E)


def _profile(reader: Reader, value: object, f_i: str, E: float) -> Stiffness | None:
    """A modulus times a second-moment profile (``I``, ``I_out`` or ``J``)."""
    spec = reader.mapping(value, f_i, required=("type",),
                          optional=("value", "A", "B", "C", "a", "b", "s", "I"))
    if spec is None:
        return None
    kind = reader.choice(spec, "type", f_i, I_TYPES)
    if kind is None:
        return None
    allowed = {"uniform": ("value",), "exponential": ("A", "B", "C", "a", "b"),
               "table": ("s", "I")}[kind]
    for key in spec:
        if key != "type" and key not in allowed:
            reader.add(join(f_i, key), f"not a parameter of I type '{kind}' "
                                       f"(allowed: {', '.join(allowed)})")
    if kind == "uniform":
        value = reader.quantity(spec, "value", f_i, "area_moment", lo=0.0, lo_open=True)
        return None if value is None else UniformEI(E * value)
    if kind == "exponential":
        coef = {k: reader.quantity(spec, k, f_i, "area_moment") for k in ("A", "B", "C")}
        rate = {k: reader.quantity(spec, k, f_i, "inverse_length") for k in ("a", "b")}
        if any(v is None for v in (*coef.values(), *rate.values())):
            return None
        return ExponentialI(E, coef["A"], coef["B"], coef["C"], rate["a"], rate["b"])
    s = reader.quantities(spec, "s", f_i, "length", lo=0.0)
    values = reader.quantities(spec, "I", f_i, "area_moment", lo=0.0, lo_open=True)
    if s is None or values is None:
        return None
    if len(s) != len(values) or len(s) < 2:
        reader.add(f_i, f"table needs at least 2 points and as many s as I values "
                        f"(got {len(s)} s and {len(values)} I)")
        return None
    if np.any(np.diff(s) <= 0):
        reader.add(join(f_i, "s"), "arc lengths must be strictly increasing")
        return None
    if s[0] != 0.0:
        reader.add(join(f_i, "s"), f"the table must start at the base, s = 0 (starts at {s[0]:g} m)")
        return None
    return TableI(E, tuple(s), tuple(values))


def _check_positive(reader: Reader, stiffness: Stiffness, length: float, field: str,
                    key: str = "I") -> None:
    """A rigidity must stay positive over the whole finger (a fitted profile may not)."""
    s = np.linspace(0.0, length, 1001)
    with np.errstate(over="ignore", invalid="ignore"):   # an overflow is reported below
        ei = stiffness.ei(s)
    if np.any(~np.isfinite(ei)) or np.any(ei <= 0):
        bad = s[np.argmax(~np.isfinite(ei) | (ei <= 0))]
        reader.add(join(field, key), f"the rigidity from {key} is not positive and finite at "
                                     f"s = {bad:g} m, inside the finger (length {length:g} m); "
                                     f"accepted: > 0 N m^2 on [0, length]")
