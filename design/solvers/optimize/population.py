"""One design for several birds: the robust design problem.

A population is a list of members, each a bird with a weight and its own
:class:`DesignSpace` (the same variables around the same grasper; only the
bird differs). A design's hold over the population is its members' holds
aggregated: ``worst`` (the shortest hold, the default) or ``mean`` (the
weighted mean). Every member has its own bruise cap (N).

The NLP of a population shares the scaled design d between the members'
single-bird NLPs (:class:`~design.solvers.optimize.transcription.DesignNLP`,
each on its own bird's schedule) and maximises an epigraph variable s:
``worst`` asks T_b ≥ s of every member's hold phase T_b (max-min as a smooth
NLP), ``mean`` asks Σ w_b T_b = s. A population of one is its member's
NLP itself, so a single-bird problem solves exactly as before.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from design.solvers.optimize.transcription import (OBJECTIVE_SCALE, DesignNLP, NLPSettings,
                                                 Rules)
from design.solvers.optimize.variables import DesignSpace

AGGREGATES = ("worst", "mean")


@dataclass(frozen=True)
class Member:
    """One bird of the population: its name, weight and design space."""

    name: str
    space: DesignSpace
    weight: float = 1.0


@dataclass(frozen=True)
class Population:
    """The members and how their holds combine (one of :data:`AGGREGATES`)."""

    members: tuple[Member, ...]
    aggregate: str = "worst"

    @classmethod
    def of(cls, space: DesignSpace) -> Population:
        """A population of one: the design problem's own bird."""
        return cls((Member(space.baseline.bird.name, space),))

    @property
    def space(self) -> DesignSpace:
        """The first member's space: the variables, their bounds and baseline."""
        return self.members[0].space

    @property
    def weights(self) -> np.ndarray:
        w = np.array([m.weight for m in self.members], float)
        return w / w.sum()

    def hold(self, holds) -> float:
        """The population's hold (s) from its members' holds, in member order."""
        holds = np.asarray(holds, float)
        if self.aggregate == "worst":
            return float(holds.min())
        return float(self.weights @ holds)


class PopulationNLP(DesignNLP):
    """The members' NLPs with the design d shared and the aggregate hold as
    objective; solved, rebound and read back like a single-bird NLP (its
    ``hold_time`` is the aggregate s, its ``peak_force`` the largest over
    the members, ``durations`` every member's phase durations in turn)."""

    def __init__(self, population: Population, schedules: list, runs: list, caps,
                 settings: NLPSettings, rules: Rules = Rules(), box=None, progress=None):
        self.population, self.settings, self.progress = population, settings, progress
        self.nlps = [DesignNLP(m.space, schedule, run, cap, settings, rules, box, progress)
                     for m, schedule, run, cap in zip(population.members, schedules, runs, caps)]
        first = self.nlps[0]
        n = self.n_design = first.n_design
        self.n_phases = sum(nlp.n_phases for nlp in self.nlps)
        d, s = ca.MX.sym("d", n), ca.MX.sym("s")
        parts, g, force, holds = [d], [], [], []
        x0, lbx, ubx = [first.x0[:n]], [first.lbx[:n]], [first.ubx[:n]]
        self._starts = []           # where each member's durations begin in x
        for b, nlp in enumerate(self.nlps):
            self._starts.append(sum(int(p.numel()) for p in parts))
            rest = ca.MX.sym(f"w{b}", nlp.x.numel() - n)
            _, g_b, force_b = nlp.functions(ca.vertcat(d, rest))
            parts.append(rest)
            g.append(g_b)
            force.append(force_b)
            holds.append(rest[nlp.hold_index - n])
            x0.append(nlp.x0[n:])
            lbx.append(nlp.lbx[n:])
            ubx.append(nlp.ubx[n:])
        horizon = max(nlp.schedule.t_end - nlp.schedule.t_start for nlp in self.nlps)
        holds0 = [nlp.x0[nlp.hold_index] for nlp in self.nlps]
        if population.aggregate == "worst":
            epigraph = ca.vertcat(*holds) - s
            lower, upper = np.zeros(len(holds)), np.full(len(holds), np.inf)
        else:
            epigraph = ca.dot(ca.DM(population.weights), ca.vertcat(*holds)) - s
            lower, upper = np.zeros(1), np.zeros(1)
        self.x = ca.vertcat(*parts, s)
        self.hold_index = int(self.x.numel()) - 1
        self.x0 = np.concatenate([*x0, [population.hold(holds0)]])
        self.lbx = np.concatenate([*lbx, [0.0]])
        self.ubx = np.concatenate([*ubx, [horizon]])
        self.g = ca.vertcat(*g, epigraph)
        self.lbg = np.concatenate([*(nlp.lbg for nlp in self.nlps), lower])
        self.ubg = np.concatenate([*(nlp.ubg for nlp in self.nlps), upper])
        self.tags = [t for nlp in self.nlps for t in nlp.tags] + ["population hold"] * len(lower)
        self._cap_rows = np.concatenate([*(nlp._cap_rows for nlp in self.nlps),
                                         np.zeros(len(lower), bool)])
        self.force = ca.vertcat(*force)
        self.f = -s / OBJECTIVE_SCALE
        self.functions = ca.Function("population", [self.x], [self.f, self.g, self.force])
        self.compiled = (all(nlp.compiled[0] for nlp in self.nlps),
                         sorted({r for nlp in self.nlps for r in nlp.compiled[1]}))
        self._size, self._solver = None, None

    def restart_contacts(self) -> None:
        for nlp in self.nlps:
            nlp.restart_contacts()

    @property
    def stage_solves(self) -> int:
        return sum(nlp.stage_solves for nlp in self.nlps)

    @property
    def size(self) -> dict:
        if self._size is None:
            self._size = {
                "variables": int(self.x.numel()), "constraints": int(self.g.numel()),
                "jacobian_nonzeros": sum(nlp.size["jacobian_nonzeros"] for nlp in self.nlps),
                "design_variables": self.n_design, "phases": self.n_phases,
                "intervals": sum(nlp.schedule.intervals for nlp in self.nlps),
                "finger_stages": int(self.force.numel()), "members": len(self.nlps)}
        return dict(self._size)

    def durations(self, x: np.ndarray) -> np.ndarray:
        return np.concatenate([x[start:start + nlp.n_phases]
                               for start, nlp in zip(self._starts, self.nlps)])

    def peaks(self, force: np.ndarray) -> np.ndarray:
        cuts = np.cumsum([nlp.force.numel() for nlp in self.nlps])[:-1]
        return np.array([p.max() if p.size else 0.0 for p in np.split(force, cuts)])

    def rebound(self, caps, box=None) -> PopulationNLP:
        """Another cap per member (N) and trust region ``box``."""
        n = self.n_design
        lo, hi = (np.zeros(n), np.ones(n)) if box is None else box
        self.lbx[:n], self.ubx[:n] = lo, hi
        rows = [np.full(nlp.g.numel(), cap) for nlp, cap in zip(self.nlps, caps)]
        rows.append(np.full(self.g.numel() - sum(r.size for r in rows), np.inf))
        self.ubg[self._cap_rows] = np.concatenate(rows)[self._cap_rows]
        return self
