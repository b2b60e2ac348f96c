"""Independent references for the beam and effective-EI tests: the classical
closed form of a uniform cantilever under a transverse dead load, and a
shooting solve of the non-uniform one, written here with scipy alone (no
code of the toolkit's solvers). Units: m, N, rad; base at the origin, the
unloaded finger along +x, the load F along +y at arc length a.

The uniform cantilever (Bisshopp & Drucker 1945): EI ψ'' = -F cos ψ with
ψ(0) = 0 and ψ'(a) = 0 integrates once to EI ψ'^2 / 2 = F (sin θ0 - sin ψ),
θ0 the load-point slope, so

    a = sqrt(EI / 2F) ∫_0^θ0 dψ / sqrt(sin θ0 - sin ψ),
    x(a) = sqrt(2 EI sin θ0 / F),
    y(a) = sqrt(EI / 2F) ∫_0^θ0 sin ψ dψ / sqrt(sin θ0 - sin ψ).

The integrals are evaluated with QUADPACK's algebraic weight (θ0 - ψ)^(-1/2)
and sin θ0 - sin ψ = 2 cos((θ0 + ψ)/2) sin((θ0 - ψ)/2), so that nothing
cancels near ψ = θ0: they are exact to about 1e-12.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import integrate, optimize

#: quadrature and integration tolerance (relative): the references below
#: are exact to about this, far below every tolerance they are used with
EXACT = 1e-12


@dataclass(frozen=True)
class LoadPoint:
    """Load point (m) and the slope there (rad)."""

    x: float
    y: float
    psi: float


def _integral(theta0: float, numerator) -> float:
    def smooth(psi):
        half = 0.5 * (theta0 - psi)
        # sqrt((θ0 - ψ) / (sin θ0 - sin ψ)), with sin(h)/h written as sinc
        return numerator(psi) / np.sqrt(np.cos(0.5 * (theta0 + psi)) * np.sinc(half / np.pi))

    value, _ = integrate.quad(smooth, 0.0, theta0, weight="alg", wvar=(0.0, -0.5),
                              epsabs=0.0, epsrel=EXACT, limit=200)
    return value


def slope_integral(theta0: float) -> float:
    """∫_0^θ0 dψ / sqrt(sin θ0 - sin ψ) (dimensionless, θ0 in (0, π/2))."""
    return _integral(theta0, lambda psi: 1.0)


def transverse_cantilever(force: float, at: float, ei: float) -> LoadPoint:
    """Load point of a uniform cantilever (EI in N m^2) under a transverse dead
    load ``force`` (N) at arc length ``at`` (m): the closed form above
    (F a^2 / EI ≤ 25)."""
    target = at * np.sqrt(2.0 * force / ei)
    # θ0 up to 1.55 rad: F a^2 / EI up to 25 (beyond, the integrand's end
    # singularity steepens towards 1 / (θ0 - ψ) and QUADPACK loses digits)
    theta0 = optimize.brentq(lambda t: slope_integral(t) - target, 1e-9, 1.55,
                             xtol=1e-15, rtol=4 * np.finfo(float).eps)
    scale = np.sqrt(ei / (2.0 * force))
    return LoadPoint(float(np.sqrt(2.0 * ei * np.sin(theta0) / force)),
                     float(scale * _integral(theta0, np.sin)), float(theta0))


def slope_matched(force: float, at: float, theta0: float) -> float:
    """The uniform EI (N m^2) whose load-point slope under ``force`` at
    ``at`` is ``theta0``: a = sqrt(EI / 2F) I(θ0) solved for EI."""
    return 2.0 * force * at ** 2 / slope_integral(theta0) ** 2


def position_matched(force: float, at: float, point: tuple[float, float],
                     bracket: tuple[float, float]) -> float:
    """The uniform EI (N m^2, within ``bracket``) whose load point under a
    transverse ``force`` at ``at`` is nearest ``point`` (m)."""
    def distance(log_ei):
        p = transverse_cantilever(force, at, float(np.exp(log_ei)))
        return float(np.hypot(p.x - point[0], p.y - point[1]))

    res = optimize.minimize_scalar(distance, bounds=np.log(bracket), method="bounded",
                                   options={"xatol": 1e-12})
    return float(np.exp(res.x))


def shoot_transverse(ei, force: float, at: float) -> LoadPoint:
    """Load point of a cantilever with rigidity ``ei(s)`` (N m^2, s in m)
    under a transverse dead load ``force`` (N) at ``at`` (m): x' = cos ψ,
    y' = sin ψ, ψ' = M / EI(s), M' = -F cos ψ from the clamp, the base moment
    M(0) found by bisection so that M(a) = 0 (it lies in (0, F a])."""
    def end(m0):
        def rhs(s, z):
            return [np.cos(z[2]), np.sin(z[2]), z[3] / ei(s), -force * np.cos(z[2])]

        sol = integrate.solve_ivp(rhs, (0.0, at), [0.0, 0.0, 0.0, m0], method="DOP853",
                                  rtol=EXACT, atol=1e-16)
        return sol.y[:, -1]

    m0 = optimize.brentq(lambda m: end(m)[3], 0.0, force * at, xtol=1e-15,
                         rtol=4 * np.finfo(float).eps)
    x, y, psi, _ = end(m0)
    return LoadPoint(float(x), float(y), float(psi))


#: the toolkit's effective EIs against :func:`effective_ei`, relative: its
#: collocation's load-point error (3e-11 m estimated) moves them by ~1e-10;
#: what is left is the two minimisers' resolution of a flat (quadratic)
#: minimum of the load-point distance, ~1e-8 (measured ≤ 1.4e-8)
EFFECTIVE_EI_REL = 1e-7


def effective_ei(ei, force: float, at: float) -> tuple[float, float]:
    """(slope-matched, position-matched) uniform EI (N m^2) standing in for
    the rigidity ``ei(s)`` under a transverse ``force`` (N) at ``at`` (m):
    :func:`shoot_transverse` for the finger, the closed form for the uniform
    beam (position match searched over 0.02-1 N m^2)."""
    end = shoot_transverse(ei, force, at)
    return (slope_matched(force, at, end.psi),
            position_matched(force, at, (end.x, end.y), (0.02, 1.0)))
