"""Effective EI: a uniform beam standing in for a non-uniform one (thesis §2.4.3).

Two definitions, for one load (F, α at arc length L):

* ``thesis``: solve the non-uniform beam, take its load-point slope ψ0, find
  the uniform EI with the same ψ0 from Frisch-Fay (eqs. 2.10b, 2.12, 2.7c),
  then multiply by the hand-calibrated C_EI = 1.48. Kept for reproduction.
* ``position`` (default): the uniform EI whose Frisch-Fay load point is
  closest to the non-uniform model's. No calibration factor: it is what the
  contact model needs (the finger must reach the object where the real one
  does).

Both are reported with the distance (m) between the stand-in's load point
and the non-uniform model's, so the cost of the approximation is visible.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np
from scipy import optimize

from design.physics.beam import Finger, PointLoad, normalise_angle
from design.physics.stiffness import UniformEI
from design.solvers.beam import solve_beam
from design.solvers.beam.frisch_fay import FrischFay, kl_of

THESIS_CALIBRATION = 1.48


@dataclass(frozen=True)
class EffectiveEI:
    """Effective EI of a finger for one load, N m^2, and the stand-ins' misfit (m)."""

    load: PointLoad
    slope_matched: float
    thesis: float
    position_matched: float
    tip_nonuniform: tuple[float, float]
    distance_slope_matched: float
    distance_thesis: float
    distance_position_matched: float

    def as_dict(self) -> dict:
        return {
            "at_m": self.load.at, "F_N": self.load.force, "alpha_rad": self.load.alpha,
            "EI_slope_matched": self.slope_matched, "EI_thesis": self.thesis,
            "EI_position_matched": self.position_matched,
            "tip_nonuniform_m": list(self.tip_nonuniform),
            "distance_slope_matched_m": self.distance_slope_matched,
            "distance_thesis_m": self.distance_thesis,
            "distance_position_matched_m": self.distance_position_matched,
        }


def slope_matched_ei(load: PointLoad, psi0: float) -> float:
    """Uniform EI whose Frisch-Fay load-point slope is ``psi0`` (steps 2-4 of §2.4.3), N m^2."""
    alpha = normalise_angle(load.alpha)
    a, p0 = (alpha, psi0) if alpha >= 0 else (-alpha, -psi0)
    d = np.pi - a - p0
    if not 0.0 < d < np.pi - a:
        raise ValueError(f"slope {psi0} rad is not on the primary branch for alpha = {alpha} rad")
    kl = float(kl_of(np.array([a]), np.array([d]), np.array([p0]))[0][0])
    return load.force * load.at ** 2 / kl ** 2


def _ff_tip(load: PointLoad, ei: float, length: float) -> np.ndarray:
    sol = FrischFay(Finger(length, UniformEI(ei)), nodes=2).solve([load])[0]
    return np.array([sol.x[-1], sol.y[-1]])


def position_matched_ei(load: PointLoad, tip: Sequence[float], length: float,
                        bracket: tuple[float, float]) -> float:
    """Uniform EI whose Frisch-Fay load point is closest to ``tip`` (m), N m^2."""
    target = np.asarray(tip, dtype=float)

    def misfit(log_ei):
        return float(np.linalg.norm(_ff_tip(load, np.exp(log_ei), length) - target))

    res = optimize.minimize_scalar(misfit, bounds=np.log(bracket), method="bounded",
                                   options={"xatol": 1e-10})
    return float(np.exp(res.x))


def effective_ei(finger: Finger, load: PointLoad, method: str = "collocation") -> EffectiveEI:
    """Both effective EIs of ``finger`` under ``load``, with their load-point misfits."""
    sol = solve_beam(finger, [load], method=method)[0]
    tip = np.array([sol.x[-1], sol.y[-1]])
    raw = slope_matched_ei(load, sol.psi[-1])
    ei_s = finger.stiffness.ei(np.linspace(0.0, load.at, 101))
    pos = position_matched_ei(load, tip, finger.length, (0.1 * ei_s.min(), 10 * ei_s.max()))

    def dist(ei):
        return float(np.linalg.norm(_ff_tip(load, ei, finger.length) - tip))

    return EffectiveEI(load, raw, THESIS_CALIBRATION * raw, pos, (float(tip[0]), float(tip[1])),
                       dist(raw), dist(THESIS_CALIBRATION * raw), dist(pos))


def effective_ei_table(finger: Finger, positions: Sequence[float], force: float,
                       alpha: float, method: str = "collocation") -> list[EffectiveEI]:
    """Effective EI against load position, like the thesis's Table 5-2 / Figure 3-4."""
    return [effective_ei(finger, PointLoad(force, alpha, at), method) for at in positions]
