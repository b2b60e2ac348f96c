"""Common machinery of the beam methods: sweeps, branch continuation, seeds.

A method solves a list of point loads on one finger. Loads are solved in
continuation order (grouped by direction and position, increasing force) so
that each starts from the previous equilibrium: the branch returned is the
one continued from the smaller load, never a jump to another equilibrium.
Iterative methods are seeded by the Frisch-Fay primary branch of the uniform
beam with the same small-deflection compliance (exact for uniform fingers);
if Newton still fails they step the load up from zero.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import replace
from typing import ClassVar, Sequence

import numpy as np

from design.physics.beam import BeamSolution, Finger, PointLoad, straight_solution
from design.physics.stiffness import UniformEI


class BeamMethod(ABC):
    """A solver for the point-loaded elastica of one finger.

    Parameters
    ----------
    finger : Finger
    nodes : int, optional
        Resolution; its meaning is method specific (see each method).
    tolerance : float, optional
        Convergence tolerance of the method's nonlinear iteration.
    """

    name: ClassVar[str]
    #: Formal convergence order of the load-point position in 1/nodes
    #: (None: exact up to root-finding, or not a discretisation).
    order: ClassVar[int | None]
    default_nodes: ClassVar[int]
    default_tolerance: ClassVar[float] = 1e-12

    def __init__(self, finger: Finger, nodes: int | None = None,
                 tolerance: float | None = None):
        self.finger = finger
        self.nodes = int(nodes or self.default_nodes)
        self.tolerance = float(tolerance or self.default_tolerance)

    def check(self) -> list[str]:
        """Reasons this method cannot solve this finger correctly (empty if it can)."""
        return []

    @abstractmethod
    def solve(self, loads: Sequence[PointLoad]) -> list[BeamSolution]:
        """Solve every load; results in the input order."""


class IterativeMethod(BeamMethod):
    """A discretised method solved by Newton iteration, load by load."""

    def solve(self, loads: Sequence[PointLoad]) -> list[BeamSolution]:
        """Solve every load, in continuation order; results in the input order."""
        loads = list(loads)
        order = sorted(range(len(loads)),
                       key=lambda i: (loads[i].alpha, loads[i].at, loads[i].force))
        out: list[BeamSolution | None] = [None] * len(loads)
        prev: BeamSolution | None = None
        for i in order:
            load = loads[i]
            same_group = prev is not None and (prev.load.alpha, prev.load.at) == (load.alpha, load.at)
            guess = prev if same_group and prev.converged and prev.load.force > 0 else None
            out[i] = prev = self.solve_one(load, guess)
        return out  # type: ignore[return-value]

    def solve_one(self, load: PointLoad, guess: BeamSolution | None = None) -> BeamSolution:
        """One load: Newton from ``guess`` (or the seed), load stepping on failure."""
        if load.force == 0.0:
            return straight_solution(load, self.name, self.nodes + 1, message="no load")
        sol = self._solve(load, guess if guess is not None else seed(self.finger, load))
        if sol.converged:
            return sol
        total = sol.iterations
        prev = None
        for f in np.linspace(0.0, load.force, 17)[1:]:
            step_load = replace(load, force=float(f))
            prev = self._solve(step_load, prev if prev is not None else seed(self.finger, step_load))
            total += prev.iterations
            if not prev.converged:
                break
        assert prev is not None
        msg = "converged by load stepping after Newton from the seed failed" if prev.converged \
            else f"did not converge, even with load stepping: {prev.message}"
        return replace(prev, load=load, iterations=total, message=msg)

    @abstractmethod
    def _solve(self, load: PointLoad, guess: BeamSolution) -> BeamSolution:
        """Newton-type solve of one nonzero load from an initial guess."""


def seed(finger: Finger, load: PointLoad, n: int = 201) -> BeamSolution:
    """Initial guess: the Frisch-Fay primary branch of the compliance-equivalent uniform beam."""
    from design.solve.beam.frisch_fay import FrischFay

    ei = finger.stiffness.compliance_equivalent(load.at)
    uniform = Finger(finger.length, UniformEI(ei))
    return FrischFay(uniform, nodes=n).solve([load])[0]


def resample(sol: BeamSolution, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """ψ and M of a solution at normalised positions u = s/L (0..1)."""
    un = sol.s / sol.s[-1] if sol.s[-1] > 0 else np.linspace(0, 1, sol.s.size)
    return np.interp(u, un, sol.psi), np.interp(u, un, sol.moment)


def richardson(fine: BeamSolution, coarse: BeamSolution, order: int, ratio: float = 2.0) -> float:
    """Load-point error estimate of ``fine`` from a coarser solution (m).

    |tip_fine - tip_coarse| / (r^p - 1) for a method of order p and mesh
    ratio r: the asymptotic error of the finer solution, times a safety
    factor 2 against pre-asymptotic meshes.
    """
    dx = fine.x[-1] - coarse.x[-1]
    dy = fine.y[-1] - coarse.y[-1]
    return float(2.0 * np.hypot(dx, dy) / (ratio ** order - 1))


def rounding_floor(sol: BeamSolution) -> float:
    """Rounding error of the cumulative sums that give x and y: n eps L (m)."""
    return float(sol.s.size * np.finfo(float).eps * sol.load.at)
