"""Flexural rigidity EI(s) of a finger along its arc length.

Conventions: ``s`` is the arc length from the clamped base in metres, EI in
N m^2. Each profile gives numeric values (numpy, vectorised), the derivative
d(EI)/ds (for the thesis's non-conservative FDM form, eq. 2.15), and a CasADi
expression in a parameter vector so that collocation and the optimiser can
treat stiffness as a variable.

References
----------
Thesis §2.2, eq. (2.33); MODEL.md §2.2 (corrected C = 3.2102e-9 m^4).
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass, replace

import casadi as ca
import numpy as np
from scipy.interpolate import CubicSpline


class Stiffness(ABC):
    """EI(s) profile of a cantilever finger (N m^2 against s in m)."""

    #: True when EI does not vary along the finger (closed forms apply).
    uniform: bool = False
    #: EI is C^k in s (None: infinitely smooth). Caps the convergence order
    #: that error estimates may assume at k + 1.
    smoothness: int | None = None

    def order_cap(self, order: int) -> int:
        """The order a method of nominal ``order`` can show on this profile."""
        return order if self.smoothness is None else min(order, self.smoothness + 1)

    @abstractmethod
    def ei(self, s: np.ndarray | float) -> np.ndarray:
        """EI at arc length(s) ``s`` (m), in N m^2."""

    @abstractmethod
    def dei(self, s: np.ndarray | float) -> np.ndarray:
        """d(EI)/ds at ``s``, in N m."""

    @property
    @abstractmethod
    def params(self) -> np.ndarray:
        """Numeric parameter vector ``p`` for :meth:`ei_casadi`."""

    @abstractmethod
    def ei_casadi(self, s: ca.SX, p: ca.SX) -> ca.SX:
        """EI(s) as a CasADi SX expression in arc length ``s`` and parameters ``p``."""

    def symbolic_key(self) -> tuple:
        """Hashable identity of :meth:`ei_casadi`'s structure (what is baked in, not ``p``)."""
        return (type(self).__name__,)

    @abstractmethod
    def scaled(self, factor: float) -> "Stiffness":
        """The same profile with EI multiplied by ``factor`` (e.g. a new E)."""

    @abstractmethod
    def describe(self) -> dict:
        """JSON-ready description (SI)."""

    def compliance_equivalent(self, at: float, n: int = 400) -> float:
        """Uniform EI with the same small-deflection load-point deflection.

        1/EI_eq = 3/L^3 ∫_0^L (L - s)^2 / EI(s) ds for a transverse load at
        s = L (unit-load method). Used to seed iterative solvers and as the
        scale of the non-dimensional moment.
        """
        s = np.linspace(0.0, at, n + 1)
        w = (at - s) ** 2 / self.ei(s)
        integral = np.trapezoid(w, s) if n else 0.0
        return at ** 3 / (3.0 * integral) if integral > 0 else float(self.ei(0.0))


@dataclass(frozen=True)
class UniformEI(Stiffness):
    """Constant flexural rigidity ``value`` (N m^2)."""

    value: float
    uniform = True

    def ei(self, s):
        return np.full_like(np.asarray(s, dtype=float), self.value)

    def dei(self, s):
        return np.zeros_like(np.asarray(s, dtype=float))

    @property
    def params(self):
        return np.array([self.value])

    def ei_casadi(self, s, p):
        return p[0] + 0 * s

    def scaled(self, factor):
        return replace(self, value=self.value * factor)

    def describe(self):
        return {"type": "uniform", "EI": self.value}

    def compliance_equivalent(self, at, n=400):
        return self.value


@dataclass(frozen=True)
class ExponentialI(Stiffness):
    """EI(s) = E (A e^(a s) + B e^(b s) + C), thesis eq. (2.33).

    E in Pa; A, B, C in m^4; a, b in 1/m.
    """

    E: float
    A: float
    B: float
    C: float
    a: float
    b: float

    def ei(self, s):
        s = np.asarray(s, dtype=float)
        return self.E * (self.A * np.exp(self.a * s) + self.B * np.exp(self.b * s) + self.C)

    def dei(self, s):
        s = np.asarray(s, dtype=float)
        return self.E * (self.A * self.a * np.exp(self.a * s) + self.B * self.b * np.exp(self.b * s))

    @property
    def params(self):
        return np.array([self.E, self.A, self.B, self.C, self.a, self.b])

    def ei_casadi(self, s, p):
        return p[0] * (p[1] * ca.exp(p[4] * s) + p[2] * ca.exp(p[5] * s) + p[3])

    def scaled(self, factor):
        return replace(self, E=self.E * factor)

    def describe(self):
        return {"type": "exponential", "E": self.E, "A": self.A, "B": self.B,
                "C": self.C, "a": self.a, "b": self.b}


@dataclass(frozen=True)
class TableI(Stiffness):
    """EI(s) = E I(s), I a cubic spline through tabulated points.

    E in Pa; ``s_knots`` (m, strictly increasing, from 0 to at least the
    finger length) and ``I_knots`` (m^4). Not-a-knot cubic spline (linear for
    two points, quadratic for three): C2, so RK4 and collocation keep order 4
    across the knots, where linear interpolation would drop them to 2.
    """

    E: float
    s_knots: tuple[float, ...]
    I_knots: tuple[float, ...]
    smoothness = 2

    def __post_init__(self):
        object.__setattr__(self, "_spline", CubicSpline(self.s_knots, self.I_knots,
                                                        bc_type="not-a-knot"))

    def _clamp(self, s):
        return np.clip(np.asarray(s, dtype=float), self.s_knots[0], self.s_knots[-1])

    def ei(self, s):
        return self.E * self._spline(self._clamp(s))

    def dei(self, s):
        return self.E * self._spline(self._clamp(s), 1)

    @property
    def params(self):
        return np.array([self.E])

    def ei_casadi(self, s, p):
        sp = self._spline
        s = ca.fmin(ca.fmax(s, self.s_knots[0]), self.s_knots[-1])
        value = None
        for i in reversed(range(sp.c.shape[1])):
            ds = s - sp.x[i]
            piece = ((sp.c[0, i] * ds + sp.c[1, i]) * ds + sp.c[2, i]) * ds + sp.c[3, i]
            value = piece if value is None else ca.if_else(s < sp.x[i + 1], piece, value)
        return p[0] * value

    def symbolic_key(self):
        return (type(self).__name__, self.s_knots, self.I_knots)

    def scaled(self, factor):
        return replace(self, E=self.E * factor)

    def describe(self):
        return {"type": "table", "E": self.E, "s": list(self.s_knots), "I": list(self.I_knots)}
