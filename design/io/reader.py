"""Reading input files field by field while collecting every problem.

A :class:`Reader` walks a parsed YAML document. Each accessor checks one
field (type, unit, range, allowed keys) and records a :class:`Problem` naming
the file, the dotted field path and the accepted values instead of raising,
so that one pass reports everything that is wrong. Callers build their
settings objects only when :meth:`Reader.ok` is true.
"""

from __future__ import annotations

import difflib
import math
from collections.abc import Iterable, Mapping

from design.errors import Problem, ProblemFileError
from design.io.units import SI_NAMES, UnitError, to_si

REQUIRED = object()


def join(field: str, key: str | int) -> str:
    """Dotted path of a child field: ``join('load', 'F') == 'load.F'``."""
    if isinstance(key, int):
        return f"{field}[{key}]"
    return f"{field}.{key}" if field else key


def interval(lo: float | None, hi: float | None, lo_open: bool, hi_open: bool) -> str:
    """Human-readable interval, e.g. ``(0, inf)`` or ``[-3.14159, 3.14159]``."""
    left = "(" if lo_open or lo is None else "["
    right = ")" if hi_open or hi is None else "]"
    a = "-inf" if lo is None else f"{lo:g}"
    b = "inf" if hi is None else f"{hi:g}"
    return f"{left}{a}, {b}{right}"


class Reader:
    """Collects problems while reading one input file."""

    def __init__(self, file: str):
        self.file = file
        self.problems: list[Problem] = []

    @property
    def ok(self) -> bool:
        return not self.problems

    def add(self, field: str, message: str) -> None:
        self.record(Problem(self.file, one_line(field), one_line(message)))

    def record(self, problem: Problem) -> None:
        """Keep ``problem`` once: two checks can find the same one (the
        mapping's required keys and the field's own reader)."""
        if problem not in self.problems:
            self.problems.append(problem)

    def raise_if_any(self) -> None:
        if self.problems:
            raise ProblemFileError(self.problems)

    def mapping(self, value: object, field: str, *, required: Iterable[str] = (),
                optional: Iterable[str] = ()) -> dict | None:
        """Check that ``value`` is a mapping with only the allowed keys.

        Unknown keys and missing required keys are each one problem; a close
        match is suggested for a misspelt key.
        """
        if not isinstance(value, Mapping):
            self.add(field or "(top level)",
                     f"expected a mapping of keys to values, got {_kind(value)}")
            return None
        required, optional = list(required), list(optional)
        allowed = required + optional
        for key in value:
            if key not in allowed:
                self.add(join(field, shown(key)),
                         f"unknown key (allowed: {', '.join(allowed)}){did_you_mean(key, allowed)}")
        for key in required:
            if key not in value:
                self.add(join(field, key), "required but missing")
        return dict(value)

    def quantity(self, data: Mapping, key: str, field: str, dimension: str, *,
                 lo: float | None = None, hi: float | None = None,
                 lo_open: bool = False, hi_open: bool = False,
                 default: object = REQUIRED) -> float | None:
        """Read a scalar with units and check it lies in the accepted range."""
        path = join(field, key)
        if key not in data:
            return self._default(path, default)
        return self._scalar(data[key], path, dimension, lo, hi, lo_open, hi_open)

    def quantities(self, data: Mapping, key: str, field: str, dimension: str, *,
                   lo: float | None = None, hi: float | None = None,
                   lo_open: bool = False, hi_open: bool = False,
                   default: object = REQUIRED) -> list[float] | None:
        """Read a scalar or a non-empty list of scalars (a sweep)."""
        path = join(field, key)
        if key not in data:
            return self._default(path, default)
        raw = data[key]
        if isinstance(raw, list):
            if not raw:
                self.add(path, "an empty list; give at least one value")
                return None
            values = [self._scalar(v, join(path, i), dimension, lo, hi, lo_open, hi_open)
                      for i, v in enumerate(raw)]
            return None if any(v is None for v in values) else values  # type: ignore[return-value]
        value = self._scalar(raw, path, dimension, lo, hi, lo_open, hi_open)
        return None if value is None else [value]

    def vectors(self, data: Mapping, key: str, field: str, dimension: str, size: int = 2, *,
                default: object = REQUIRED) -> list[tuple[float, ...]] | None:
        """Read one vector ``[x, y]`` or a list of them (a sequence of poses)."""
        path = join(field, key)
        if key not in data:
            return self._default(path, default)
        raw = data[key]
        if isinstance(raw, list) and raw and not isinstance(raw[0], list):
            raw = [raw]
        if not isinstance(raw, list) or not raw:
            self.add(path, f"expected [x, y] or a list of [x, y], got {_kind(raw)}")
            return None
        out = []
        for i, item in enumerate(raw):
            where = path if len(raw) == 1 else join(path, i)
            if not isinstance(item, list) or len(item) != size:
                self.add(where, f"expected a list of {size} numbers, got {_kind(item)}")
                return None
            values = [self._scalar(v, join(where, j), dimension, None, None, False, False)
                      for j, v in enumerate(item)]
            if any(v is None for v in values):
                return None
            out.append(tuple(values))
        return out

    def choice(self, data: Mapping, key: str, field: str, options: Iterable[str],
               default: object = REQUIRED) -> str | None:
        """Read a string that must be one of ``options``."""
        path = join(field, key)
        options = list(options)
        if key not in data:
            return self._default(path, default, f" (one of: {', '.join(options)})")
        value = data[key]
        if value not in options:
            self.add(path, f"'{value}' is not one of: {', '.join(options)}"
                           f"{did_you_mean(value, options)}")
            return None
        return value

    def integer(self, data: Mapping, key: str, field: str, *, lo: int | None = None,
                hi: int | None = None, default: object = REQUIRED) -> int | None:
        """Read an integer in ``[lo, hi]``."""
        path = join(field, key)
        if key not in data:
            return self._default(path, default)
        value = data[key]
        if isinstance(value, bool) or not isinstance(value, int):
            self.add(path, f"expected an integer in {interval(lo, hi, False, False)}, "
                           f"got {value!r}")
            return None
        if (lo is not None and value < lo) or (hi is not None and value > hi):
            self.add(path, f"{value} is outside the accepted range "
                           f"{interval(lo, hi, False, False)}")
            return None
        return value

    def boolean(self, data: Mapping, key: str, field: str, default: object = REQUIRED) -> bool | None:
        path = join(field, key)
        if key not in data:
            return self._default(path, default)
        if not isinstance(data[key], bool):
            self.add(path, f"expected true or false, got {data[key]!r}")
            return None
        return data[key]

    def text(self, data: Mapping, key: str, field: str, default: object = REQUIRED) -> str | None:
        path = join(field, key)
        if key not in data:
            return self._default(path, default)
        if not isinstance(data[key], str):
            self.add(path, f"expected a string, got {_kind(data[key])}")
            return None
        return data[key]

    def _default(self, path: str, default: object, hint: str = "") -> object:
        """A key's value when it is absent: its default, or None and a
        problem when it is required (``hint``: what it may be)."""
        if default is REQUIRED:
            self.add(path, f"required but missing{hint}")
            return None
        return default

    def _scalar(self, raw: object, path: str, dimension: str, lo: float | None,
                hi: float | None, lo_open: bool, hi_open: bool) -> float | None:
        try:
            value = to_si(raw, dimension)
        except UnitError as exc:
            self.add(path, f"{exc}; expected a number in SI "
                           f"({SI_NAMES[dimension] or 'dimensionless'}) or a string with a unit")
            return None
        too_low = lo is not None and (value < lo or (lo_open and value == lo))
        too_high = hi is not None and (value > hi or (hi_open and value == hi))
        if too_low or too_high or math.isnan(value):
            unit = SI_NAMES[dimension]
            suffix = f" {unit}" if unit else ""
            self.add(path, f"{value:g}{suffix} is outside the accepted range "
                           f"{interval(lo, hi, lo_open, hi_open)}{suffix}")
            return None
        return value


def one_line(text: str) -> str:
    """``text`` with unprintable characters (a newline, a carriage return in a
    key) escaped, so that every problem prints as one line."""
    return "".join(c if c.isprintable() else repr(c)[1:-1] for c in text)


def shown(key: object) -> str:
    """A key as it appears in a field path: as written, or quoted when it is
    empty or has surrounding spaces."""
    text = str(key)
    return text if text and text.strip() == text else repr(text)


def did_you_mean(given: object, allowed: list[str]) -> str:
    """'; did you mean 'x'?' for a close spelling or a name containing the given one."""
    text = str(given)
    hint = difflib.get_close_matches(text, allowed, n=1)
    if not hint:
        hint = [a for a in allowed if text and (text in a or a in text)][:1]
    return f"; did you mean '{hint[0]}'?" if hint else ""


def _kind(value: object) -> str:
    if value is None:
        return "nothing"
    return {dict: "a mapping", list: "a list", str: f"the text {value!r}"}.get(
        type(value), f"{type(value).__name__} {value!r}")
