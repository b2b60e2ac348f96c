"""The pattern search: a design loop whose every decision survives round-off.

The trust-region loop (:mod:`trust_region`) moves to wherever Ipopt's
iterate stands when its iteration limit stops it; on the grasp NLP, far from
converged at that limit, the iterate follows Ipopt's line-search and filter
decisions, and round-off (another CPU's BLAS kernels, compiled against
interpreted functions, a baseline changed in its ninth digit) flips one and
gives another design. This loop uses the simulator alone and visits only the
points of a lattice around the start, ``d = clip(d0 + k / n)`` with
integer ``k`` (scaled variables; ``n`` = 64 unless the problem states its
``lattice``), so two runs can differ only where a comparison of two
simulated holds or of a peak with the cap flips:

* where the problem asks for a survey (``solver.survey``), the search first
  simulates that many points of a scrambled Sobol sequence in the box
  (seed 0: a multistart's starts are its first points), together, and
  starts from the best of them that beats the baseline and holds longer
  (the first of equals), else from the baseline: a local search from the
  baseline alone ends on the optimum nearest it, and the hold has many;
* a coordinate search with a step of ``n / 8`` lattice units (1/8 of each
  box), halved down to one unit: for each variable in the problem's order it simulates one
  step up and one down; the better of the two (up on a tie) is taken if it
  beats the incumbent, and the search keeps going that way, each step twice
  the last (at most 1/8 of the box), two steps simulated together, while each
  beats the last; a sweep that moves nothing halves the step;
* "beats" is :func:`~trust_region.better` with a band: a longer hold by more
  than :data:`HOLD_BAND` (0.1 ms: a smaller gain is not worth a move, and
  the band keeps two near-equal holds from being ordered by round-off),
  every finger under the cap (no tolerance: the verification allows 1 %
  for its finer resolution) and under its fold force, no jam;
* the search's simulations are the loop's (rtol 1e-6, steps no longer than
  the optimiser's grid): the cap is decided on the peak force, and a looser
  tolerance can step over a force transient of a few ms at a contact;
* a budget of designs evaluated ends the search, as deterministically;
* a design whose run would be one already simulated takes that one's
  score without a simulation (design/solvers/optimize/scenes.py): one of
  the same scene (a belt that does not slow, polled at another start or
  rate), or one that differs from the current design only in fingers its
  run never reached, which stay clear of the bird where it puts them;
* a candidate is ruled out as soon as one of its runs shows that it cannot
  beat the incumbent (one bird, or a population's worst hold, once the
  incumbent keeps every limit): a finger over its limit, or a hold no
  longer than the incumbent's. That run ends there
  (design/solvers/grasp/cutoff.py), and a population's other birds are
  not simulated: the incumbent's shortest-held bird is simulated first,
  alone (it rules most candidates out: the one that limits the incumbent
  limits its neighbours), and only if it does not, the other birds
  together. The search takes the same steps as with every run whole: a
  ruled-out candidate beats nothing, and its whole runs would not have
  beaten the incumbent, nor (its hold at most the incumbent's, the other's
  longer by more than the band) a candidate polled beside it that does; a
  candidate ruled out against one incumbent is ruled out against any
  later, better one;
* the simulations of a poll or an extension (two designs' birds, or one
  design's) are handed out one bird at a time to two forked processes
  where there are two cores, and a core they leave free starts on the next
  three polls' runs, as they would be asked for if this evaluation moves
  nothing, as most do not (design/solvers/optimize/ahead.py): the same
  simulations as one process would run, and the same record.

The search's claim for its design is its own simulation of it; the
verification simulates it again at 4x finer resolution (steps a quarter of
the grid's, tolerances 256x tighter) and must agree within 2 % on the hold.
The trust-region loop's claim, the collocation NLP with the design fixed,
is not asked for: it can stall short of feasibility on a design two
simulations agree on, and a claim that cannot be made would fail it.
"""

from __future__ import annotations

import copy
import resource
import time
from dataclasses import dataclass, replace
from functools import partial

import numpy as np

from design.solvers.grasp.cutoff import Cutoff
from design.solvers.optimize.ahead import Ahead
from design.solvers.optimize.forked import processes
from design.solvers.optimize.line import faster, rate_of
from design.solvers.optimize.multistart import starting_designs
from design.solvers.optimize.population import Population
from design.solvers.optimize.profile import SIMULATIONS, Profile
from design.solvers.optimize.scenes import Scenes, same_run
from design.solvers.optimize.transcription import Rules, rule_margins
from design.solvers.optimize.trust_region import (Evaluated, LoopSettings, Outcome, Scored,
                                                   alone, better, caps_text, caps_value,
                                                   check_baseline, population_of, simulate)
from design.solvers.optimize.variables import DesignSpace

#: the default lattice: each variable's box in this many units; a coarser
#: one (a power of two, at least :data:`FIRST_STEP`) takes the finer one's
#: steps, until one is clipped at the box's edge, and ends where the finer
#: one's step first falls below its unit
LATTICE = LoopSettings.lattice
#: the first step is 1/FIRST_STEP of each box
FIRST_STEP = 8
#: the survey's Sobol seed: a multistart's default (its starts are the
#: survey's first points)
SURVEY_SEED = 0
#: the polls whose points may run ahead on a free core
AHEAD_POLLS = 3
#: a move must lengthen the hold by more than this (s)
HOLD_BAND = 1e-4
#: the default budget of designs evaluated
MAX_SIMULATIONS = LoopSettings.max_simulations


@dataclass
class Trial:
    """One evaluated lattice point: its scaled design, its value, and the
    move that reached it (variable index, step in lattice units, ``poll`` or
    ``extend``; a survey's point: no variable, no step, ``survey``) and
    whether the search took it (a survey's: started from it)."""

    d: np.ndarray
    value: object
    variable: int | None
    units: int
    move: str
    taken: bool = False


@dataclass
class Searched:
    """A search's answer: the best point and its value, every trial in
    order, and whether no step of one lattice unit beats the answer."""

    d: np.ndarray
    value: object
    trials: list[Trial]
    lattice_optimum: bool


def compass(evaluate_many, d0: np.ndarray, value0, beats, allowed=lambda d: True,
            max_evaluations: int = MAX_SIMULATIONS, moved=None, enough=None,
            lattice: int = LATTICE) -> Searched:
    """The coordinate search of the module's docstring on the lattice
    ``clip(d0 + k / lattice, 0, 1)`` (scaled variables, integer ``k``).

    ``evaluate_many(designs, incumbent, ahead)`` gives the values of a list
    of designs (the caller may evaluate them in parallel, and start on
    ``ahead``, the designs it will probably be asked for next; a value that
    cannot beat the ``incumbent``'s may be marked ``ruled_out_by`` and left
    partial), ``value0`` is ``d0``'s;
    ``beats(a, b)`` says whether value a is better than b; a design that is
    not ``allowed`` is not tried; ``moved(trial, count)`` hears of every
    step taken; the search ends at the first point (``d0`` or a step taken)
    whose value is ``enough``. Every decision is a ``beats`` of two values,
    so the path depends on the values only through those decisions."""
    d0 = np.asarray(d0, float)
    first = lattice // FIRST_STEP
    lo, hi = -np.ceil(d0 * lattice).astype(int), np.ceil((1 - d0) * lattice).astype(int)
    seen: dict[tuple, object] = {(0,) * len(d0): value0}
    trials: list[Trial] = []
    trial_at: dict[tuple, Trial] = {}

    def point(k):
        return np.clip(d0 + np.asarray(k) / lattice, 0.0, 1.0)

    def step(k, i, units):
        moved_k = list(k)
        moved_k[i] = min(max(k[i] + units, lo[i]), hi[i])
        return tuple(moved_k)

    def unseen(points) -> list[tuple]:
        return [p for p in dict.fromkeys(points) if p not in seen]

    def evaluate(tried: list[tuple], i: int, move: str) -> list:
        """The values of ``tried``'s points ((k, units) pairs), the unseen ones
        evaluated together, as many as the budget allows (None beyond it);
        the next polls' points, should this evaluation move nothing, go
        with them as the ones probably asked for next."""
        new = unseen(p for p, _ in tried)[:max(0, max_evaluations - len(seen))]
        if new:
            room = max(0, max_evaluations - len(seen) - len(new))
            ahead = [point(p) for p in upcoming(i)][:room]
            for p, v in zip(new, evaluate_many([point(p) for p in new], seen[k], ahead)):
                seen[p] = v
                trial_at[p] = Trial(point(p), v, i, dict(tried)[p], move)
                trials.append(trial_at[p])
        return [seen.get(p) for p, _ in tried]

    class Enough(Exception):
        """A step reached a point whose value is enough."""

    def take(k):
        trial_at[k].taken = True
        if moved:
            moved(trial_at[k], len(seen))
        if enough and enough(seen[k]):
            raise Enough

    def valid(t, k) -> bool:
        return t != k and allowed(point(t))

    def upcoming(i: int) -> list[tuple]:
        """The unseen points of the next :data:`AHEAD_POLLS` polls that have
        any after variable i's, should the search stay where it is (a sweep
        without a move halves the step)."""
        n, out, polls = len(d0), [], 0
        for j in range(i + 1, i + 1 + n):
            size = units if j < n or any_move else units // 2
            if size < 1:
                break
            new = unseen(t for u in (size, -size) if valid(t := step(k, j % n, u), k))
            if new:
                out += new
                polls += 1
                if polls == AHEAD_POLLS:
                    break
        return out

    k, units, cut, any_move = (0,) * len(d0), first, False, False

    def sweeps():
        """Poll and extend until the step falls below one unit or the budget ends."""
        nonlocal k, units, cut, any_move
        while units >= 1 and len(seen) < max_evaluations:
            any_move, cut = False, False
            for i in range(len(d0)):
                tries = [(t, u) for u in (units, -units) if valid(t := step(k, i, u), k)]
                values = evaluate(tries, i, "poll") if tries else []
                cut = cut or any(v is None for v in values)
                if not values or values[0] is None:
                    continue
                best = 0 if len(values) == 1 or values[1] is None or \
                    not beats(values[1], values[0]) else 1
                if not beats(values[best], seen[k]):
                    continue
                (k, ext), any_move = tries[best], True
                take(k)
                # keep going that way, each step twice the last (up to the first
                # step), two at a time: the pair is evaluated together
                while True:
                    e1 = min(2 * abs(ext), first) * (1 if ext > 0 else -1)
                    e2 = min(2 * abs(e1), first) * (1 if ext > 0 else -1)
                    a = step(k, i, e1)
                    if not valid(a, k):
                        break
                    b = step(a, i, e2)
                    pair = [(a, e1)] + ([(b, e2)] if valid(b, a) else [])
                    va, *vb = evaluate(pair, i, "extend")
                    if va is None or not beats(va, seen[k]):
                        break
                    k = a
                    take(k)
                    if not vb or vb[0] is None or not beats(vb[0], va):
                        break
                    k, ext = b, e2
                    take(k)
            if not any_move:
                units //= 2

    if enough and enough(value0):
        units, cut = 0, True
    else:
        try:
            sweeps()
        except Enough:                  # ended where it is enough: no lattice optimum claimed
            units, cut = 0, True
    # a lattice optimum: the last sweep, at one unit, polled every neighbour
    return Searched(point(k), seen[k], trials, units < 1 and not cut)


def search(space: DesignSpace | Population, cap, settings: LoopSettings,
           rules: Rules = Rules(), start=None, progress=None, anchor: bool = True,
           workers: int | None = None) -> Outcome:
    """Maximise the (population's) hold under the cap (N; one per bird, or one
    for all) by :func:`compass` from ``start`` (scaled; with ``anchor`` a
    start worse than the baseline gives way to it); by default from the
    baseline, or with ``settings.survey`` from the best of the baseline and
    the :func:`survey`'s points. A point that breaks a design rule the
    baseline keeps is not tried. The points evaluated together are simulated
    by ``workers`` processes (by default one per core, at most two:
    :class:`Pairs`); the answer does not depend on how many.
    ``settings.max_simulations`` designs evaluated (the survey's among them)
    end the search."""
    t0 = time.perf_counter()
    max_simulations, unit = settings.max_simulations, 1 / settings.lattice
    profile = Profile()
    say = progress or (lambda message: None)
    population = population_of(space)
    caps = np.broadcast_to(np.asarray(cap, float), (len(population.members),)).copy()
    beats, rivals = judges(population, caps, settings)
    pool = Pairs(population, settings, settings.simulator, workers, rivals)

    def simulated(designs, incumbent=None, ahead=()):
        with profile.phase(SIMULATIONS):
            return pool.score(designs, incumbent, ahead)
    scenes = Scenes(simulated, population.space.scene_key, partial(same_run, population))

    d0 = population.space.scale(population.space.base_values)
    allowed = allowed_by(population.space, rules)
    baseline, = scenes.score([d0])
    check_baseline(population, baseline)
    origin, first = d0, baseline
    if start is not None:
        started, = scenes.score([np.asarray(start, float)])
        if not (anchor and beats(baseline, started)):
            origin, first = started.d, started
    names = [v.name for v in population.space.variables]
    say(f"baseline: hold {baseline.hold:.4f} s, peak finger force {baseline.peak:.2f} N "
        f"(cap {caps_text(caps)}); pattern search, steps of {1 / FIRST_STEP:g} to "
        f"{unit:g} of each box")

    def moved(trial: Trial, count: int):
        line = f"{rate_of(trial.value):.1f} birds/min, " \
            if settings.objective == "throughput" else ""
        say(f"step {abs(trial.units) * unit:g}: {names[trial.variable]} "
            f"{'up' if trial.units > 0 else 'down'} -> {line}hold {trial.value.hold:.4f} s, "
            f"peak {trial.value.peak:.2f} N ({count} designs evaluated)")

    with pool:
        surveyed = survey(scenes.score, d0, baseline, beats, allowed, settings.survey) \
            if start is None and settings.survey else []
        chosen = next((t for t in surveyed if t.taken), None)
        if chosen:
            origin, first = chosen.d, chosen.value
        if surveyed:
            say(f"survey: {len(surveyed)} Sobol points of the box; "
                + (f"starting from the best, hold {first.hold:.4f} s, peak {first.peak:.2f} N"
                   if chosen else "none beats the baseline with a longer hold"))
        found = compass(scenes.score, origin, first, beats, allowed,
                        max_simulations - len(surveyed), moved, lattice=settings.lattice)
    out = Outcome(found.value, baseline, caps, profile=profile)
    source = (f"the pattern search's simulation (rtol {settings.simulator.rtol:g}, steps up "
              f"to the grid's)")
    out.claims = [(m.hold, source) for m in found.value.members]
    out.claim = found.value.hold, source
    out.iterations = [{
        "iteration": n + 1, "radius": abs(t.units) * unit, "move": t.move,
        "variable": None if t.variable is None else names[t.variable],
        "direction": int(np.sign(t.units)),
        "candidate_scaled": t.d.tolist(), "simulated_hold_time_s": t.value.hold,
        "simulated_peak_force_N": t.value.peak, "accepted": t.taken,
        "same_run": scenes.repeated(t.d),
        **({} if len(caps) == 1 else {
            "simulated_hold_times_s": per_bird(population, t.value, "hold"),
            "simulated_peak_forces_N": per_bird(population, t.value, "peak")}),
        **({} if settings.objective == "throughput" else {
            "ruled_out_by": t.value.ruled_out_by, "stopped": stopped(t.value)}),
        **({} if settings.objective != "throughput" else {
            "line_rate_per_min": rate_of(t.value), "keeps_limits": t.value.within(caps),
            "jammed_birds": t.value.shortfall(caps)[1]})}
        for n, t in enumerate(surveyed + found.trials)]
    out.search = {"method": "pattern", "lattice": unit, "first_step": 1 / FIRST_STEP,
                  "hold_band_s": HOLD_BAND, "rtol": settings.simulator.rtol,
                  "simulations": len(surveyed) + len(found.trials) + 1 + (start is not None)
                  - len(scenes.repeats), "survey": len(surveyed),
                  "same_runs": len(scenes.repeats),
                  "bird_simulations": pool.simulations,
                  "max_simulations": max_simulations, "lattice_optimum": found.lattice_optimum,
                  "processes": pool.processes, "runs_ahead": pool.ran_ahead,
                  "processes_cpu_time_s": pool.children_cpu_time,
                  "caps_N": caps_value(caps)}
    out.trials = surveyed + found.trials
    out.wall_time = time.perf_counter() - t0
    return out


def survey(score, d0: np.ndarray, baseline, beats, allowed, points: int) -> list[Trial]:
    """The first ``points`` points of the scrambled Sobol sequence in the
    box (:func:`~design.solvers.optimize.multistart.starting_designs`' seed,
    so a multistart's starts are its first points) that keep the design
    rules, scored together by ``score(designs, incumbent)`` against the
    ``baseline`` (scaled start ``d0``). Of those that ``beat`` it and
    hold longer than it by more than :data:`HOLD_BAND` (a design that
    keeps limits the baseline breaks by holding nothing is no start), the
    best, the first of equals, is marked taken: the search starts there."""
    designs = [d for d in starting_designs(d0, points + 1, SURVEY_SEED)[1:] if allowed(d)]
    trials = [Trial(d, value, None, 0, "survey")
              for d, value in zip(designs, score(designs, baseline))]
    best = None
    for t in trials:
        if beats(t.value, baseline) and t.value.hold > baseline.hold + HOLD_BAND and \
                (best is None or beats(t.value, best.value)):
            best = t
    if best:
        best.taken = True
    return trials


def judges(population: Population, caps: np.ndarray, settings: LoopSettings):
    """How the search compares designs: ``beats(a, b)``, in which a
    ruled-out candidate beats nothing and anything else beats it; and, where
    the hold counts (one bird, or the population's worst),
    ``rivals(incumbent)``: None where the incumbent breaks a limit (then a
    candidate's every run counts whole), else each bird's
    :class:`~design.solvers.grasp.cutoff.Cutoff`, the incumbent's hold and
    the bird's cap: a bird's run that breaks its limits or holds no longer
    rules the candidate out."""
    def beats(a: Scored, b: Scored) -> bool:
        if a.ruled_out_by or b.ruled_out_by:
            return not a.ruled_out_by
        if settings.objective == "throughput":
            return faster(a, b, caps, settings.min_hold, HOLD_BAND)
        return better(a, b, caps, tolerance=0.0, band=HOLD_BAND)

    def rivals(incumbent: Scored) -> list[Cutoff] | None:
        if not incumbent.within(caps):
            return None
        return [Cutoff(incumbent.hold, float(cap)) for cap in caps]
    lazy = settings.objective != "throughput" and (
        population.aggregate == "worst" or len(population.members) == 1)
    return beats, rivals if lazy else None


def rules_out(run: Evaluated, member, cutoff: Cutoff) -> bool:
    """Does one bird's run show that its candidate cannot beat ``cutoff``'s
    rival: ended by it, or over a limit, or holding no longer?"""
    return bool(run.run.summary.get("stopped")) or run.hold <= cutoff.hold \
        or not alone(run, member).within(cutoff.cap)


def stopped(value: Scored) -> str | None:
    """Why the run that ruled a candidate out ended early (None: the
    candidate was not ruled out, or by a whole run)."""
    return next((e.run.summary.get("stopped") for m, e in
                 zip(value.population.members, value.members)
                 if m.name == value.ruled_out_by), None)


def per_bird(population: Population, value: Scored, what: str) -> list:
    """Each bird's hold (s) or peak (N), ``what``, in the population's order;
    None for a bird a ruled-out candidate did not simulate."""
    simulated = {id(m): getattr(e, what) for m, e in zip(value.population.members,
                                                          value.members)}
    return [simulated.get(id(m)) for m in population.members]


def _simulate_slim(job: tuple[np.ndarray, int, Cutoff | None], scoring: tuple) -> Evaluated:
    """Bird ``b``'s simulation of the scaled design ``d``, ended early against
    ``cutoff`` (``job``), slim, by ``scoring``'s population, settings and
    integrator."""
    population, settings, integrator = scoring
    d, b, cutoff = job
    return slim(simulate(population.members[b].space, d, settings, integrator, cutoff))


def _job_key(job: tuple[np.ndarray, int, Cutoff | None]) -> tuple:
    """What a job computes: the design's bits, the bird and the rival."""
    d, b, cutoff = job
    return np.asarray(d, float).tobytes(), b, cutoff


def slim(run: Evaluated) -> Evaluated:
    """A bird's simulation without its trajectories (tens of MB each): what a
    search decides by (the run's setup and summary) passes between processes."""
    summary = run.run.summary
    run.run = copy.copy(run.run)
    run.run.trajectory, run.run.windows = None, None
    run.run.__dict__["summary"] = summary
    return run


class Pairs:
    """Simulates the designs a search evaluates together (a poll's two, an
    extension's two) for every bird, one bird of one design at a time, in
    forked processes, or here where there is one core, no ``fork``, or this
    process is a daemon (a Dask worker's) that may not have children. A
    forked child computes exactly what this process would. A core left free
    starts the runs the search will probably ask for next (``ahead``),
    each used only if asked for as it ran: the same design, bird and rival.

    With ``rivals`` (an incumbent -> each bird's Cutoff, or None where the
    incumbent admits none; :func:`judges`) each run ends where it shows
    that its candidate cannot beat the incumbent, and a candidate's first
    bird is the incumbent's shortest-held, alone; its other birds are
    simulated only if that one does not rule it out (the same birds on any
    number of processes)."""

    def __init__(self, population: Population, settings: LoopSettings, integrator,
                 workers: int | None, rivals=None):
        self.job = (population, settings, integrator)
        self.processes = processes(workers)
        self.rivals = rivals
        self.pool: Ahead | None = None
        #: runs started ahead that were then asked for, and those never asked
        #: for (None: no forked processes)
        self.ran_ahead: dict | None = None
        #: the birds simulated (one design, one bird each)
        self.simulations = 0
        #: the CPU time (s) of the forked processes, once they have ended
        #: (this process's own is in the run's profile)
        self.children_cpu_time = 0.0

    def __enter__(self) -> Pairs:
        if self.processes > 1:
            self._children_before = _children_cpu()
            # the forked processes inherit the function: nothing is pickled
            self.pool = Ahead(lambda job: _simulate_slim(job, self.job), _job_key,
                              self.processes)
        return self

    def __exit__(self, *exc) -> None:
        if self.pool is not None:
            self.pool.close()
            self.ran_ahead = {"used": self.pool.used, "unused": self.pool.unused}
            self.pool = None
            self.children_cpu_time = _children_cpu() - self._children_before

    def _simulate(self, jobs: list[tuple[np.ndarray, int, Cutoff | None]], ahead=()
                  ) -> list[Evaluated]:
        self.simulations += len(jobs)
        if self.pool is None:
            return [_simulate_slim(job, self.job) for job in jobs]
        return self.pool.run(jobs, ahead)

    def score(self, designs: list, incumbent: Scored | None = None, ahead: list = ()
              ) -> list[Scored]:
        """Each design scored for the population; candidates that cannot beat
        the ``incumbent`` partly, ``ruled_out_by`` the bird that shows it.
        ``ahead``: designs the caller will probably score next against the
        same incumbent, whose first runs a free core may start meanwhile."""
        population = self.job[0]
        birds = range(len(population.members))
        cutoffs = self.rivals(incumbent) if self.rivals and incumbent else None
        order = sorted(birds, key=lambda b: (incumbent.holds[b], b)) if cutoffs else list(birds)

        def first(b_done: dict) -> list[int]:
            """A candidate's birds to simulate next: if it may be ruled out, its
            first bird alone, then the rest."""
            return [b for b in order if b not in b_done][:1 if cutoffs and not b_done else None]
        later = [(d, b, cutoffs and cutoffs[b]) for d in ahead for b in first({})]
        runs: list[dict] = [{} for _ in designs]
        out: list[Scored | None] = [None] * len(designs)
        while pending := [i for i, o in enumerate(out) if o is None]:
            jobs = [(i, b) for i in pending for b in first(runs[i])]
            for (i, b), run in zip(jobs, self._simulate(
                    [(designs[i], b, cutoffs and cutoffs[b]) for i, b in jobs], later)):
                runs[i][b] = run
            for i in pending:
                ruled = [b for b in order if b in runs[i] and cutoffs and
                         rules_out(runs[i][b], population.members[b], cutoffs[b])]
                if ruled or len(runs[i]) == len(order):
                    simulated = [b for b in birds if b in runs[i]]
                    out[i] = Scored(np.asarray(designs[i], float),
                                    [runs[i][b] for b in simulated],
                                    population if len(simulated) == len(order) else
                                    replace(population, members=tuple(
                                        population.members[b] for b in simulated)),
                                    population.members[ruled[0]].name if ruled else None)
        return out


def _children_cpu() -> float:
    """User and system CPU time (s) of this process's ended, waited-for children."""
    used = resource.getrusage(resource.RUSAGE_CHILDREN)
    return used.ru_utime + used.ru_stime


def allowed_by(space: DesignSpace, rules: Rules):
    """Whether a scaled design keeps every design rule the baseline keeps."""
    kept_at_start = keeps(space, space.scale(space.base_values), rules)

    def allowed(d) -> bool:
        return all(kept or not before for kept, before in
                   zip(keeps(space, d, rules), kept_at_start))
    return allowed


def keeps(space: DesignSpace, d: np.ndarray, rules: Rules) -> list[bool]:
    """Does the scaled design ``d`` keep each design rule (5.3-5.7)?"""
    return [margin >= -1e-9 for margin, _ in rule_margins(space.values(d), space.baseline,
                                                            rules)]
