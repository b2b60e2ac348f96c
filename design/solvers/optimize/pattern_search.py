"""The pattern search: a design loop whose every decision survives round-off.

The trust-region loop (:mod:`trust_region`) moves to wherever Ipopt's
iterate stands when its iteration limit stops it; on the grasp NLP, far from
converged at that limit, the iterate follows Ipopt's line-search and filter
decisions, and round-off (another CPU's BLAS kernels, compiled against
interpreted functions, a baseline changed in its ninth digit) flips one and
gives another design. This loop uses the simulator alone and visits only the
points of a lattice around the start, ``d = clip(d0 + k / 64)`` with
integer ``k`` (scaled variables), so two runs can differ only where a
comparison of two simulated holds or of a peak with the cap flips:

* a coordinate search with a step of 8 lattice units (1/8 of each box),
  then 4, 2, 1: for each variable in the problem's order it simulates one
  step up and one down; the better of the two (up on a tie) is taken if it
  beats the incumbent, and the search keeps stepping that way while each
  step beats it; a sweep that moves nothing halves the step;
* "beats" is :func:`~trust_region.better` with a band: a longer hold by more
  than :data:`HOLD_BAND` (0.1 ms, ten times the search simulator's error
  on the hold), every finger under the cap (no tolerance: the verification
  allows 1 % for its finer resolution) and under its fold force, no jam;
* the search's simulations are the scene's integrator with rtol 1e-4 and
  steps no longer than the optimiser's grid: the decisions need holds to
  0.1 ms, not the trust-region loop's 1e-6 (whose views must reproduce
  them), and it halves the cost of a simulation;
* a budget of simulations ends the search, as deterministically.

The best design is simulated again with the loop's own simulator, so that
its fixed-design NLP view (the optimiser's claim) and the 4x finer
verification judge it exactly as they judge a trust-region design.
"""

from __future__ import annotations

import time
from dataclasses import replace

import numpy as np

from design.solvers.optimize.population import Population
from design.solvers.optimize.profile import SIMULATIONS, Profile
from design.solvers.optimize.transcription import Rules, rule_margins
from design.solvers.optimize.trust_region import (LoopSettings, Outcome, Scored, better,
                                                   caps_text, caps_value, population_of, score)
from design.solvers.optimize.variables import DesignSpace

#: the lattice's unit and the first step, in lattice units (scaled variables)
LATTICE, FIRST_STEP = 1 / 64, 8
#: a move must lengthen the hold by more than this (s)
HOLD_BAND = 1e-4
#: the search simulator's relative tolerance
SEARCH_RTOL = 1e-4
#: the default budget of simulations
MAX_SIMULATIONS = 150


class Lattice:
    """The points ``clip(d0 + LATTICE * k, 0, 1)`` and their simulations, by ``k``."""

    def __init__(self, d0: np.ndarray, simulate):
        self.d0 = np.asarray(d0, float)
        self.lo = -np.ceil(self.d0 / LATTICE).astype(int)
        self.hi = np.ceil((1 - self.d0) / LATTICE).astype(int)
        self.simulate = simulate
        self.seen: dict[tuple, Scored] = {}

    def point(self, k: np.ndarray) -> np.ndarray:
        return np.clip(self.d0 + LATTICE * k, 0.0, 1.0)

    def step(self, k: np.ndarray, i: int, units: int) -> np.ndarray:
        """``k`` moved ``units`` along variable ``i``, stopped at the box."""
        moved = k.copy()
        moved[i] = min(max(k[i] + units, self.lo[i]), self.hi[i])
        return moved

    def __call__(self, k: np.ndarray) -> Scored:
        key = tuple(int(x) for x in k)
        if key not in self.seen:
            self.seen[key] = self.simulate(self.point(k))
        return self.seen[key]


def search(space: DesignSpace | Population, cap, settings: LoopSettings,
           rules: Rules = Rules(), start=None, progress=None, anchor: bool = True,
           max_simulations: int = MAX_SIMULATIONS) -> Outcome:
    """Maximise the (population's) hold under the cap (N; one per bird, or one
    for all) from ``start`` (scaled; the baseline by default; with ``anchor``
    a start worse than the baseline gives way to it). A point that breaks a
    design rule the baseline keeps is not tried."""
    t0 = time.perf_counter()
    profile = Profile()
    say = progress or (lambda message: None)
    population = population_of(space)
    caps = np.broadcast_to(np.asarray(cap, float), (len(population.members),)).copy()
    searching = replace(settings.simulator, rtol=max(settings.simulator.rtol, SEARCH_RTOL))

    def simulate(d):
        with profile.phase(SIMULATIONS):
            return score(population, d, settings, searching)

    def beats(a: Scored, b: Scored) -> bool:
        return better(a, b, caps, tolerance=0.0, band=HOLD_BAND)

    d0 = population.space.scale(population.space.base_values)
    kept_at_start = keeps(population.space, d0, rules)

    def allowed(lattice: Lattice, k: np.ndarray) -> bool:
        return all(kept or not before for kept, before in
                   zip(keeps(population.space, lattice.point(k), rules), kept_at_start))
    base = Lattice(d0, simulate)
    k0 = np.zeros(len(d0), int)
    baseline = base(k0)
    failed = [f"{m.name}: {e.run.summary['message']}" for m, e in
              zip(population.members, baseline.members) if not e.run.summary["ok"]]
    if failed:
        raise ValueError("the baseline's simulation ended early, so no design can start from "
                         "it: " + "; ".join(failed))
    lattice = base
    if start is not None:
        started = Lattice(start, simulate)
        if not (anchor and beats(baseline, started(k0))):
            lattice = started
    names = [v.name for v in population.space.variables]
    out = Outcome(baseline, baseline, caps, profile=profile)
    k, step = k0, FIRST_STEP
    say(f"baseline: hold {baseline.hold:.4f} s, peak finger force {baseline.peak:.2f} N "
        f"(cap {caps_text(caps)}); pattern search, steps of 1/{round(1 / (LATTICE * step))} "
        f"to 1/{round(1 / LATTICE)} of each box")

    def record(kind: str, i: int, units: int, tried: Scored, taken: bool):
        out.iterations.append({
            "iteration": len(out.iterations) + 1, "radius": units * LATTICE, "move": kind,
            "variable": names[i], "candidate_scaled": tried.d.tolist(),
            "simulated_hold_time_s": tried.hold, "simulated_peak_force_N": tried.peak,
            "accepted": taken, **({} if len(caps) == 1 else {
                "simulated_hold_times_s": tried.holds.tolist(),
                "simulated_peak_forces_N": tried.peaks.tolist()})})

    def budget_left() -> bool:
        return len(lattice.seen) < max_simulations

    while step >= 1 and budget_left():
        moved = False
        for i in range(len(k)):
            tries = [(units, lattice.step(k, i, units)) for units in (step, -step)]
            tries = [(units, t) for units, t in tries
                     if not np.array_equal(t, k) and allowed(lattice, t)]
            if not tries or not budget_left():
                continue
            scored = [(units, t, lattice(t)) for units, t in tries]
            units, t, s = scored[0]
            if len(scored) == 2 and beats(scored[1][2], s):
                units, t, s = scored[1]
            for u, _, tried in scored:
                record("poll", i, u, tried, tried is s and beats(s, lattice(k)))
            while beats(s, lattice(k)):
                k, moved = t, True
                say(f"step 1/{round(1 / (LATTICE * step))}: {names[i]} "
                    f"{'up' if units > 0 else 'down'} -> hold {s.hold:.4f} s, peak "
                    f"{s.peak:.2f} N ({len(lattice.seen)} simulations)")
                t = lattice.step(k, i, units)
                if np.array_equal(t, k) or not allowed(lattice, t) or not budget_left():
                    break
                s = lattice(t)
                record("extend", i, units, s, beats(s, lattice(k)))
        if not moved:
            step //= 2
    with profile.phase(SIMULATIONS):
        final = score(population, lattice(k).d, settings)
    out.best = final
    if lattice is base and not k.any():
        out.baseline = final      # nothing beat the baseline: the answer is the baseline
    out.search = {"method": "pattern", "lattice": LATTICE, "first_step": FIRST_STEP * LATTICE,
                  "hold_band_s": HOLD_BAND, "rtol": searching.rtol,
                  "simulations": len(lattice.seen), "max_simulations": max_simulations,
                  "lattice_optimum": step < 1, "caps_N": caps_value(caps)}
    out.wall_time = time.perf_counter() - t0
    return out


def keeps(space: DesignSpace, d: np.ndarray, rules: Rules) -> list[bool]:
    """Does the scaled design ``d`` keep each design rule (5.3-5.7)?"""
    return [margin >= -1e-9 for margin, _ in rule_margins(space.values(d), space.baseline,
                                                            rules)]
