"""The feasibility screen: can any design hold a population's hardest bird, within its limits?

A robust design must keep every bird within its limits: its cap, its
fingers' fold forces, no jam. The population's pattern search pays one
simulation per bird for every design it tries. Where the baseline breaks a
bird's limits, the screen first asks a cheaper question of the bird
furthest from them at the baseline (:meth:`Scored.shortfall`'s order:
failed runs, then jams, then the largest force over a limit). No design
holds the population better than the baseline unless it keeps that bird
within its limits, and, for the shortest hold (``worst``), holds it longer
than the baseline holds its worst bird: a design that does not lift the
bird at all keeps it within its limits and holds nobody.

* The pattern search runs on that bird alone, from each of several starts
  (the baseline and points of a scrambled Sobol sequence, as a multistart's:
  design/solvers/optimize/multistart.py), comparing designs by their
  distance from the goal (:func:`distance`): a design that lifts the bird
  and presses too hard is nearer than one that keeps its limits by never
  lifting it. Each start ends at the first design that reaches the goal, or
  when its budget of simulations is spent; the starts are tried in turn,
  and the first that reaches the goal ends the screen.
* Each simulation has the loop's budget of contact work
  (:data:`~design.solvers.optimize.trust_region.LOOP_NEWTON_SOLVES`): one
  past it stops and counts as a failed run.
* A design that reaches it starts the population's search.
* If no start reaches one, the population's search is not run: the answer
  is each start's best, the best of them simulated for every bird. It is
  the evidence of a local search from each start, not a proof over the
  whole box: the result names the starts, the designs simulated and where
  each ended.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from design.solvers.optimize.pattern_search import HOLD_BAND, Pairs, allowed_by, compass
from design.solvers.optimize.population import Population
from design.solvers.optimize.transcription import Rules
from design.solvers.optimize.trust_region import (FORCE_BAND, LOOP_NEWTON_SOLVES, LoopSettings,
                                                   Outcome, Scored, alone, score)

#: the loop's budget of contact work for the 4x finer verification of a
#: screen's answer (four times the steps): an answer the screen could not
#: improve fails its run anyway, and its verification must end
VERIFY_NEWTON_SOLVES = 4 * LOOP_NEWTON_SOLVES
#: ``solver.search.method`` of a run the screen answered
METHOD = "feasibility screen"
#: the screen's starts and each one's budget of simulations, by default:
#: the baseline and three Sobol points, each given 16 simulations (its own
#: and about one poll of eight variables at the first step)
STARTS, SIMULATIONS = 4, 16


def hardest_bird(baseline: Scored, caps, tolerance: float) -> int | None:
    """The bird furthest from its limits (cap in N, fold forces, no jam) at
    ``baseline`` in :meth:`Scored.shortfall`'s order, the first of equals;
    None where every bird keeps them within ``tolerance`` (relative)."""
    caps = np.broadcast_to(np.asarray(caps, float), (len(baseline.members),))
    if baseline.within(caps, tolerance):
        return None
    shortfalls = [alone(run, member).shortfall(cap, tolerance) for run, member, cap
                  in zip(baseline.members, baseline.population.members, caps)]
    return max(range(len(shortfalls)), key=lambda b: (shortfalls[b], -b))


@dataclass
class Screened:
    """One start of the screen: where it started and ended (scaled designs),
    the end's value (the bird alone), how many designs it simulated, whether
    the end keeps the bird within its limits, and whether it reaches the
    screen's goal (within them, and held long enough)."""

    start: np.ndarray
    d: np.ndarray
    value: Scored
    simulations: int
    within: bool
    reached: bool

    def row(self, cap: float) -> dict:
        """What a case keeps of it (JSON), SI: the shortfall as
        :meth:`Scored.shortfall` gives it, failed runs, jams, N over a limit."""
        failed, jammed, over = self.value.shortfall(cap)
        summary = self.value.run.summary
        return {"start": self.start.tolist(), "d": self.d.tolist(), "within": self.within,
                "reached": self.reached, "simulations": self.simulations,
                "failed_runs": failed, "jammed": jammed,
                "over_limit_N": over, "hold_time_s": self.value.hold,
                "max_finger_force_N": self.value.peak,
                "max_finger_force_finger": summary["max_finger_force_finger"],
                "jam": "; ".join(summary["jam"]) or "none"}


def screen(bird: Population, cap: float, settings: LoopSettings, rules: Rules,
           start: np.ndarray, budget: int = SIMULATIONS, beyond: float | None = None,
           workers: int | None = None) -> Screened:
    """The pattern search on one ``bird`` (a population of one) from the
    scaled ``start`` under ``cap`` (N), ending at the first design within its
    limits that holds it longer than ``beyond`` (s; None: any hold), or
    after ``budget`` simulations (the start's included)."""
    start = np.asarray(start, float)
    pool = Pairs(bird, settings, settings.simulator, workers)

    def beats(a: Scored, b: Scored) -> bool:
        return nearer(distance(*a.shortfall(cap), a.hold, beyond),
                      distance(*b.shortfall(cap), b.hold, beyond))

    def reached(value: Scored) -> bool:
        return value.within(cap) and holds_beyond(value.hold, beyond)

    with pool:
        first, = pool.score([start])
        found = compass(pool.score, start, first, beats, allowed_by(bird.space, rules),
                        budget, enough=reached, lattice=settings.lattice)
    return Screened(start, found.d, found.value, len(found.trials) + 1,
                    found.value.within(cap), reached(found.value))


def holds_beyond(hold: float, beyond: float | None) -> bool:
    """Does a hold (s) count towards the screen's goal: longer than
    ``beyond`` by more than the search's band (None: any hold)?"""
    return beyond is None or hold > beyond + HOLD_BAND


def distance(failed: int, jammed: int, over: float, hold: float, beyond: float | None) -> tuple:
    """How far a design is from the screen's goal, in the order the screen
    compares designs: failed runs, jammed birds, whether it fails to hold
    the bird beyond ``beyond``, the force over a limit (N; none within
    them), then the shorter hold (s, negated). A design that keeps the
    bird within its limits by never lifting it is no nearer to holding it
    than one that lifts it and presses too hard: the screen asks for both.
    ``failed, jammed, over``: :meth:`Scored.shortfall`'s."""
    return failed, jammed, not holds_beyond(hold, beyond), max(over, 0.0), -hold


def nearer(a: tuple, b: tuple) -> bool:
    """Is distance ``a`` nearer the goal than ``b``: the counts and the hold
    flag exactly, the force over a limit by more than :data:`FORCE_BAND`, the
    hold by more than the search's band, as
    :func:`~design.solvers.optimize.trust_region.better` compares."""
    if a[:3] != b[:3]:
        return a[:3] < b[:3]
    if abs(a[3] - b[3]) > FORCE_BAND:
        return a[3] < b[3]
    return a[4] < b[4] - HOLD_BAND


def best_row(rows: list[dict]) -> int:
    """The screen row nearest its goal (:func:`distance`), the first of equals."""
    return min(range(len(rows)), key=lambda i: (distance(
        rows[i]["failed_runs"], rows[i]["jammed"], rows[i]["over_limit_N"],
        rows[i]["hold_time_s"], rows[i]["beyond_s"]), i))


def unreached(population: Population, caps, settings: LoopSettings, rows: list[dict],
              bird: str) -> Outcome:
    """The answer where no start of the screen reached its goal for
    ``bird``: the best start's design, simulated for every bird as the
    search simulates, its own simulation as the claim; ``search`` holds the
    screen's every start."""
    caps = np.broadcast_to(np.asarray(caps, float), (len(population.members),)).copy()
    k = best_row(rows)
    best = score(population, np.array(rows[k]["d"]), settings, workers=None)
    out = Outcome(best, None, caps)
    source = "the feasibility screen's simulation (as the pattern search simulates)"
    out.claims = [(m.hold, source) for m in best.members]
    out.claim = best.hold, source
    out.search = {"method": METHOD, "bird": bird, "starts": rows, "best": k,
                  "simulations": sum(r["simulations"] for r in rows) + len(population.members),
                  "rtol": settings.simulator.rtol, "caps_N": caps.tolist()}
    return out


def answered(search: dict | None) -> bool:
    """Did the screen answer the run whose ``solver.search`` this is?"""
    return (search or {}).get("method") == METHOD


def verification_budget(search: dict | None) -> float | None:
    """The contact-work budget of a design's verification: the screen's
    answer's (:data:`VERIFY_NEWTON_SOLVES`), none for a search's."""
    return VERIFY_NEWTON_SOLVES if answered(search) else None
