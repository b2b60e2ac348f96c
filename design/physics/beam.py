"""The large-deflection cantilever finger under a point load (thesis ch. II).

Finger frame: clamped at the origin, straight along +x when unloaded, arc
length s (m), slope ψ(s) (rad). A force of magnitude F (N) acts at arc length
L (``at``) with direction angle α:

    F_vec = F (-cos α, sin α)          α = π/2: transverse push in +y

First-order form (MODEL.md §2), with M the bending moment (N m):

    x' = cos ψ,  y' = sin ψ,  ψ' = M / EI(s),  M' = F_x sin ψ - F_y cos ψ
    x(0) = y(0) = ψ(0) = 0,  M(L) = 0

Beyond the load point the finger is straight.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from design.physics.rod import RUBBER_POISSON
from design.physics.stiffness import Stiffness


@dataclass(frozen=True)
class Finger:
    """A compliant finger: length (m) and flexural rigidity profiles.

    ``stiffness`` is EI(s) for bending in the finger's plane (towards y, the
    soft direction: the planar model's only one). The spatial rod
    (design/physics/rod.py) also needs ``stiff``, EI about the section's
    other axis (bending towards z), and ``torsion``, GJ(s); each defaults to
    a round section's: EI_out = EI, GJ = EI / (1 + ν) (J = 2 I,
    G = E / (2 (1 + ν)), ν = 0.5 for rubber).
    """

    length: float
    stiffness: Stiffness
    name: str = ""
    stiff: Stiffness | None = None
    torsion: Stiffness | None = None

    @property
    def stiffness_out(self) -> Stiffness:
        """EI(s) for bending out of the finger's plane (N m²)."""
        return self.stiffness if self.stiff is None else self.stiff

    @property
    def torsion_rigidity(self) -> Stiffness:
        """GJ(s) (N m²)."""
        if self.torsion is not None:
            return self.torsion
        return self.stiffness.scaled(1.0 / (1.0 + RUBBER_POISSON))

    def scaled(self, factor: float) -> "Finger":
        """The same finger in a material ``factor`` times stiffer (a new E)."""
        return replace(self, stiffness=self.stiffness.scaled(factor),
                       stiff=None if self.stiff is None else self.stiff.scaled(factor),
                       torsion=None if self.torsion is None else self.torsion.scaled(factor))

    def describe(self) -> dict:
        out = {"name": self.name, "length": self.length, "stiffness": self.stiffness.describe()}
        if self.stiff is not None:
            out["stiffness_out_of_plane"] = self.stiff.describe()
        if self.torsion is not None:
            out["torsion"] = self.torsion.describe()
        return out


@dataclass(frozen=True)
class PointLoad:
    """Point force on the finger: magnitude ``force`` (N, ≥ 0), direction
    ``alpha`` (rad, force = F(-cos α, sin α) in the finger frame), applied at
    arc length ``at`` (m)."""

    force: float
    alpha: float
    at: float

    @property
    def components(self) -> tuple[float, float]:
        """(F_x, F_y) in the finger frame, N."""
        return -self.force * np.cos(self.alpha), self.force * np.sin(self.alpha)


@dataclass(frozen=True)
class BeamSolution:
    """Equilibrium shape of the loaded part of a finger, 0 ≤ s ≤ L.

    Arrays ``s, x, y, psi, moment`` share one length; the last entry is the
    load point. ``error_estimate`` (m) bounds the load-point position error
    of this solution against the exact solution of the model the method
    solves (for small-deflection: against the elastica).
    """

    load: PointLoad
    method: str
    s: np.ndarray
    x: np.ndarray
    y: np.ndarray
    psi: np.ndarray
    moment: np.ndarray
    error_estimate: float
    converged: bool
    branch: str
    iterations: int = 0
    message: str = ""
    #: True/False where the method could tell whether another equilibrium
    #: exists for this load; None where it could not.
    multiple_equilibria: bool | None = None
    extras: dict = field(default_factory=dict)

    @property
    def tip(self) -> tuple[float, float, float]:
        """(x, y, ψ) of the load point in the finger frame (m, m, rad)."""
        return float(self.x[-1]), float(self.y[-1]), float(self.psi[-1])

    def base_moment_error(self) -> float:
        """|M(0) - (x_c F_y - y_c F_x)| in N m: equilibrium of the whole beam."""
        fx, fy = self.load.components
        return abs(float(self.moment[0]) - (self.x[-1] * fy - self.y[-1] * fx))


def rhs(s: np.ndarray, state: np.ndarray, load: PointLoad, stiffness: Stiffness) -> np.ndarray:
    """d/ds of state (x, y, ψ, M) for the first-order elastica (any shape of trailing axes)."""
    _, _, psi, m = state
    fx, fy = load.components
    return np.array([np.cos(psi), np.sin(psi), m / stiffness.ei(s),
                     fx * np.sin(psi) - fy * np.cos(psi)])


def straight_solution(load: PointLoad, method: str, n: int = 2, branch: str = "straight",
                      message: str = "") -> BeamSolution:
    """The undeflected finger (F = 0, pure tension, or axial load below buckling)."""
    s = np.linspace(0.0, load.at, n)
    z = np.zeros_like(s)
    fx, fy = load.components
    moment = (load.at - s) * fy  # zero unless F has a transverse part
    return BeamSolution(load, method, s, s.copy(), z, z.copy(), moment, 0.0, True, branch,
                        message=message, multiple_equilibria=False)


def normalise_angle(alpha: float) -> float:
    """α mapped into (-π, π]."""
    a = (alpha + np.pi) % (2 * np.pi) - np.pi
    return np.pi if a == -np.pi else a


def classify_branch(alpha: float, psi: np.ndarray, tol: float = 1e-9) -> str:
    """Name the equilibrium branch from the slope along the finger.

    For a load with a transverse part (sin α ≠ 0): ``primary`` when the
    finger bends to the side the transverse force pushes it (ψ sin α ≥ 0
    throughout), the branch connected to F = 0; ``secondary`` otherwise, bent
    against the force, reachable only past a fold (near-axial loads above
    the buckling range). For a purely axial load: ``straight`` while
    |ψ| ≤ ``tol`` (rad), else ``buckled+``/``buckled-`` by the tip's side.
    """
    span = float(np.max(np.abs(psi))) if psi.size else 0.0
    a = normalise_angle(alpha)
    if a in (0.0, np.pi):
        if span <= tol:
            return "straight"
        return "buckled+" if psi[-1] > 0 else "buckled-"
    direction = np.sign(np.sin(a))
    return "primary" if np.all(direction * psi >= -tol * span) else "secondary"
