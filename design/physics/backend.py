"""One formula, two number types: numpy for the simulator, CasADi for the optimiser.

The physics modules write each formula once against the small set of
operations below; :func:`ops` picks the numpy set for numbers and arrays and
the CasADi set as soon as one argument is symbolic (SX or MX), so the
optimiser's constraints are the simulator's equations, not a copy of them.

>>> import casadi as ca
>>> float(ops(1.0).sqrt(4.0)), ops(ca.SX.sym("x")).name
(2.0, 'casadi')
"""

from __future__ import annotations

import casadi as ca
import numpy as np

_SYMBOLIC = (ca.SX, ca.MX)


class _Numeric:
    name = "numpy"
    cos, sin, sqrt, atan2, exp = np.cos, np.sin, np.sqrt, np.arctan2, np.exp
    fmin, fmax = np.minimum, np.maximum

    @staticmethod
    def matrix(rows):
        return np.array(rows, dtype=float)

    @staticmethod
    def vector(items):
        return np.array(items, dtype=float)

    @staticmethod
    def concat(parts):
        return np.concatenate([np.atleast_1d(p) for p in parts])

    @staticmethod
    def solve(A, b):
        return np.linalg.solve(A, b)

    @staticmethod
    def if_else(cond, a, b):
        return a if cond else b


class _Symbolic:
    name = "casadi"
    cos, sin, sqrt, atan2, exp = (staticmethod(f) for f in (ca.cos, ca.sin, ca.sqrt,
                                                            ca.atan2, ca.exp))
    fmin, fmax = staticmethod(ca.fmin), staticmethod(ca.fmax)

    @staticmethod
    def matrix(rows):
        return ca.vertcat(*[ca.horzcat(*row) for row in rows])

    @staticmethod
    def vector(items):
        return ca.vertcat(*items)

    @staticmethod
    def concat(parts):
        return ca.vertcat(*parts)

    @staticmethod
    def solve(A, b):
        return ca.solve(A, b)

    @staticmethod
    def if_else(cond, a, b):
        return ca.if_else(cond, a, b)


NUMERIC, SYMBOLIC = _Numeric(), _Symbolic()


def is_symbolic(*values) -> bool:
    return any(isinstance(v, _SYMBOLIC) for v in values)


def ops(*values):
    """The operation set for these values: CasADi if any is symbolic."""
    return SYMBOLIC if is_symbolic(*values) else NUMERIC


def read_only(value):
    """A numpy array made read-only (cached values that callers share);
    anything else as it is."""
    if isinstance(value, np.ndarray):
        value.setflags(write=False)
    return value
