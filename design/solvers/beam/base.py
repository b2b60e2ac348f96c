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

from design.physics.beam import BeamSolution, Finger, PointLoad, normalise_angle, straight_solution
from design.physics.stiffness import UniformEI


#: branches a solve may return: connected to F = 0 (for α = 0, past the
#: Euler load, the buckled shape is taken on the +y side by convention)
CONTINUED_BRANCHES = ("primary", "straight", "buckled+")


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
    #: Convergence order in 1/nodes that the error estimate assumes: the
    #: nominal order, or less where that is not reached in practice (None:
    #: exact up to root-finding, or not a discretisation).
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
        order = continuation_order(loads)
        out: list[BeamSolution | None] = [None] * len(loads)
        prev: BeamSolution | None = None
        for i in order:
            load = loads[i]
            same_group = prev is not None and (prev.load.alpha, prev.load.at) == (load.alpha, load.at)
            guess = prev if same_group and prev.converged and prev.load.force > 0 else None
            out[i] = prev = self.solve_one(load, guess)
        return out  # type: ignore[return-value]

    def solve_one(self, load: PointLoad, guess: BeamSolution | None = None) -> BeamSolution:
        """One load on the branch continued from F = 0.

        Newton from ``guess`` (the previous load of a sweep), else from the
        seed; if that fails or lands on another branch (a warm start near a
        buckling load can), from the seed; then by load stepping from zero.
        """
        if load.force == 0.0:
            return straight_solution(load, self.name, self.nodes + 1, message="no load")
        if normalise_angle(load.alpha) == 0.0:
            return self._finish(self._axial(load))
        tries = [guess, None] if guess is not None else [None]
        total = 0
        for start in tries:
            sol = self._solve(load, start if start is not None else seed(self.finger, load))
            total += sol.iterations
            if sol.converged and sol.branch in CONTINUED_BRANCHES:
                return self._finish(replace(sol, iterations=total))
        prev = None
        for f in np.linspace(0.0, load.force, 17)[1:]:
            step_load = replace(load, force=float(f))
            prev = self._solve(step_load, prev if prev is not None else seed(self.finger, step_load))
            total += prev.iterations
            if not prev.converged:
                break
        assert prev is not None
        ok = prev.converged and prev.branch in CONTINUED_BRANCHES
        msg = ("converged by load stepping after Newton from the seed failed" if ok else
               f"no equilibrium on the continued branch found, even by load stepping "
               f"(last: branch {prev.branch}; {prev.message or 'converged'})")
        return self._finish(replace(prev, load=load, iterations=total, converged=ok, message=msg))

    def _axial(self, load: PointLoad) -> BeamSolution:
        """Pure compression: straight below the buckling load, buckled (+y) above.

        A non-uniform finger buckles no earlier than a uniform one with its
        smallest EI, so below that Euler load the answer is straight; above,
        Newton starts from that beam's buckled shape. If it finds none, the
        straight state is returned as not converged: it is an equilibrium,
        but unstable, and not the branch continued from F = 0. (Past the
        smallest-EI Euler load the finger may still be below its own, where
        straight is right, but this method cannot tell.)
        """
        ei_min = float(np.min(self.finger.stiffness.ei(np.linspace(0.0, load.at, 201))))
        if load.force * load.at ** 2 / ei_min <= (np.pi / 2) ** 2:
            return straight_solution(load, self.name, self.nodes + 1,
                                     message="axial compression below the buckling load")
        sol = self._solve(load, seed(self.finger, load, ei=ei_min))
        if sol.converged and sol.branch == "buckled+":
            return sol
        failed = sol.message or f"Newton converged to the {sol.branch} branch"
        straight = straight_solution(
            load, self.name, self.nodes + 1,
            message=f"axial compression past the smallest-EI Euler load: no buckled equilibrium "
                    f"found ({failed}); the straight shape returned may be unstable")
        return replace(straight, converged=False, multiple_equilibria=None)

    def _finish(self, sol: BeamSolution) -> BeamSolution:
        """Say whether another equilibrium exists, where that is known (uniform EI)."""
        if not self.finger.stiffness.uniform or sol.multiple_equilibria is not None:
            return sol
        from design.solvers.beam.frisch_fay import FrischFay

        ff = FrischFay(self.finger, nodes=2).solve([sol.load])[0]
        return replace(sol, multiple_equilibria=ff.multiple_equilibria)

    def _solve(self, load: PointLoad, guess: BeamSolution) -> BeamSolution:
        """Solve at the method's resolution and at half of it; the pair gives
        the error estimate (Richardson, order capped by the stiffness's
        smoothness), plus the nonlinear solve's and rounding's share."""
        fine = self._discrete(load, guess, coarse=False)
        if not fine.converged:
            return fine
        coarse = self._discrete(load, fine, coarse=True)
        return self._with_estimate(fine, (coarse.x[-1], coarse.y[-1]) if coarse.converged else None,
                                   self._resolution(coarse))

    def _with_estimate(self, fine: BeamSolution, coarse_tip: tuple[float, float] | None,
                       coarse_resolution: float) -> BeamSolution:
        """``fine`` with its error estimate from the load point (m) of a solve at
        ``coarse_resolution`` (inf when that solve failed)."""
        if coarse_tip is None:
            return replace(fine, error_estimate=np.inf)
        ratio = self._resolution(fine) / coarse_resolution
        order = self.finger.stiffness.order_cap(self.order)
        est = float(richardson((fine.x[-1], fine.y[-1]), coarse_tip, order, ratio))
        return replace(fine, error_estimate=est + self._solve_error(fine) + rounding_floor(fine))

    @abstractmethod
    def _discrete(self, load: PointLoad, guess: BeamSolution, coarse: bool) -> BeamSolution:
        """Newton solve of one nonzero load at the full (or half) resolution."""

    @abstractmethod
    def _resolution(self, sol: BeamSolution) -> float:
        """Number of mesh steps a discrete solution used."""

    def _solve_error(self, sol: BeamSolution) -> float:
        """Load-point error left by the nonlinear solve (m); 0 where it converges to rounding."""
        return 0.0


def continuation_order(loads: Sequence[PointLoad]) -> list[int]:
    """Indices of ``loads`` grouped by direction and position, force increasing."""
    return sorted(range(len(loads)), key=lambda i: (loads[i].alpha, loads[i].at, loads[i].force))


def seed(finger: Finger, load: PointLoad, n: int = 201, ei: float | None = None) -> BeamSolution:
    """Initial guess: the Frisch-Fay primary branch of a uniform beam, by default
    the one with the same small-deflection compliance."""
    from design.solvers.beam.frisch_fay import FrischFay

    if ei is None:
        ei = finger.stiffness.compliance_equivalent(load.at)
    uniform = Finger(finger.length, UniformEI(ei))
    return FrischFay(uniform, nodes=n).solve([load])[0]


def resample(sol: BeamSolution, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """ψ and M of a solution at normalised positions u = s/L (0..1)."""
    un = sol.s / sol.s[-1] if sol.s[-1] > 0 else np.linspace(0, 1, sol.s.size)
    return np.interp(u, un, sol.psi), np.interp(u, un, sol.moment)


def richardson(fine_tip, coarse_tip, order: int, ratio: float = 2.0):
    """Load-point error estimate (m) of a solution from a coarser one's
    (tips as (x, y); arrays of tips give an array of estimates).

    |tip_fine - tip_coarse| / (r^p - 1) for a method of order p and mesh
    ratio r: the asymptotic error of the finer solution, times a safety
    factor 2 against pre-asymptotic meshes.
    """
    dx = fine_tip[0] - coarse_tip[0]
    dy = fine_tip[1] - coarse_tip[1]
    return 2.0 * np.hypot(dx, dy) / (ratio ** order - 1)


def rounding_floor(sol: BeamSolution) -> float:
    """Rounding error of the cumulative sums that give x and y: n eps L (m)."""
    return float(sol.s.size * np.finfo(float).eps * sol.load.at)
