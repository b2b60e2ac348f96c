"""The design loop: simulate, transcribe, optimise, simulate again.

Each outer iteration builds the NLP of :mod:`transcription` around the
current design's simulated schedule, lets Ipopt move the design within a
trust region (a box of half-width Δ in the scaled variables), and
re-simulates the candidate with the forward simulator. A candidate that
keeps every finger under the cap and holds longer is accepted and Δ grows;
otherwise Δ shrinks, and if the simulator saw a higher peak than the NLP
the NLP's cap is backed off by the ratio (at most 10% per iteration).

The NLP's cap starts below the true cap, by ``cap_margin`` (25 %), and the
margin halves at every outer iteration (3 % by the fourth). A baseline
that sits on its cap (``cap: baseline``) leaves the NLP no room: every
direction that lengthens the hold first raises some finger's force, and on
the fixed schedule the NLP only sees the local trade. With the margin, the
first steps move to designs well inside the cap, where the simulation can
find the different contact sequences (merged N = 0 windows) that hold
longer, and the later steps use the slack as the margin closes
(docs/design-method.md). The schedule (contact and belt modes) is rebuilt
around every accepted design, so contacts the NLP could not see are found
by the simulation.

A candidate is accepted only if the optimiser's grid reproduces its
simulation: the NLP with the design fixed, on the design's *own* schedule,
tracking the simulated phase durations, must converge and give the same
hold time within 2 %. That number is the optimiser's claim for the design;
an independent simulation at a 4x finer resolution must confirm it (hold
time within 2 %, peak force within 1 % over the cap) for the run to pass.

After a rejected candidate the next NLP is the last one with the new cap
and trust region (its schedule is the best design's, unchanged), not a new
build.

The loop times itself (``Outcome.profile``: simulations, each NLP's
construction, Ipopt and CasADi's function statistics, the fixed-design
views; design/solvers/optimize/profile.py) without changing what it computes.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field, replace

import numpy as np

from design.solvers.grasp.cutoff import Cutoff
from design.solvers.grasp.integrate import IntegratorSettings
from design.solvers.grasp.simulation import GraspRun, simulate_grasp
from design.solvers.grasp.validity import finger_limits, validity_problems
from design.solvers.optimize.forked import forked_map
from design.solvers.optimize.population import Member, Population, PopulationNLP
from design.solvers.optimize.profile import CONSTRUCTION, OPTIMISER, SIMULATIONS, VIEWS, Profile
from design.solvers.optimize.schedule import schedule_of
from design.solvers.optimize.transcription import DesignNLP, NLPResult, NLPSettings, Rules
from design.solvers.optimize.variables import DesignSpace

#: verification tolerances: hold time (relative) and force over the cap (relative)
HOLD_TOLERANCE, CAP_TOLERANCE = 0.02, 0.01
#: Ipopt iterations allowed for the optimiser's view of a fixed design, and
#: how many without progress in feasibility stop it: a view that reproduces
#: its simulation converges well within the limit, one that cannot stalls
#: at a visible violation, and the stall test stops it early instead of
#: letting it run to the limit
VIEW_MAX_ITER, VIEW_STALL = 100, 15
#: the NLP's cap is lowered by at most this factor per rejected candidate
BACK_OFF = 0.9


#: each loop simulation's budget of the belt continuations' Newton solves
#: (where the chord method did not converge) per simulated second
#: (IntegratorSettings.max_newton_solves): Table 5-5's birds at the baseline
#: make 1.9-3.8 a second, the main job's designs at most 15 in a 1.6 s run; a
#: finger pressed to where its quasi-static contact ends (a fold it snaps
#: through at every trial of a step, a touch with no consistent contact)
#: makes them by the hundred within tenths of a second (measured while a
#: trial still cut its step near a fold, 13 Newton solves where it now makes
#: 4: the multistart's runs that ended ok made at most 72, those stopped by
#: the budget passed its 480 between 1.07 and 1.24 s), and such a
#: simulation, unstopped, ran for 10 s to minutes where 2 s is usual. A run stopped by
#: it is a failed run, the worst a design can be; the count is the same on
#: every machine, unlike a wall-time limit.
LOOP_NEWTON_SOLVES = 300
#: the loop's simulator is tighter than a grasp scene's default (rtol 1e-4):
#: its accept/reject decisions compare holds a few ms apart and its views
#: must reproduce them within 2 % (docs/design-method.md). Its steps are no
#: longer than the NLP's time grid (a design problem's own grid:
#: design/solvers/optimize/policy.py)
LOOP_SIMULATOR = IntegratorSettings(rtol=1e-6, atol=1e-8, max_step=NLPSettings.time_step,
                                    max_newton_solves=LOOP_NEWTON_SOLVES)


@dataclass(frozen=True)
class LoopSettings:
    """Outer iterations, the first trust-region half-width (scaled variables)
    and the simulator used between NLPs."""

    nlp: NLPSettings = field(default_factory=NLPSettings)
    outer_iterations: int = 6
    radius: float = 0.15
    min_radius: float = 0.01
    simulator: IntegratorSettings = field(default_factory=lambda: LOOP_SIMULATOR)
    contact_nodes: int = 6
    #: the NLP's cap starts this fraction below the true cap and the margin
    #: halves at every outer iteration (continuation; see :func:`optimise`)
    cap_margin: float = 0.25
    #: "trust-region" (this module's loop) or "pattern" (design/solvers/
    #: optimize/pattern_search.py: the same answer under round-off)
    method: str = "trust-region"
    #: the pattern search's budget: designs simulated (each for every bird)
    max_simulations: int = 150
    #: the pattern search's lattice: each variable's box in this many units
    #: (its finest step; a power of two from 8)
    lattice: int = 64
    #: the pattern search's survey: from the baseline it first simulates
    #: this many points of a scrambled Sobol sequence in the box and starts
    #: from the best of them and the baseline (0: from the baseline; a
    #: power of two)
    survey: int = 0
    #: ``hold`` (the longest hold) or ``throughput`` (the highest line rate
    #: with every bird held ``min_hold`` s: design/solvers/optimize/line.py)
    objective: str = "hold"
    min_hold: float = 0.0


@dataclass
class Evaluated:
    """A design and its simulation."""

    d: np.ndarray
    run: GraspRun

    @property
    def hold(self) -> float:
        return self.run.summary["hold_time_s"]

    @property
    def peak(self) -> float:
        return self.run.summary["max_finger_force_N"]


@dataclass
class Scored:
    """A design simulated for every bird of a population: ``hold`` is the
    population's (its aggregate), ``peaks`` each bird's largest finger force
    (N), ``run`` the limiting bird's simulation (the only one for one bird)."""

    d: np.ndarray
    members: list[Evaluated]
    population: Population
    #: a search's candidate whose birds were simulated only until one of
    #: them showed that it cannot beat the search's incumbent: that bird's
    #: name (``members`` and ``population`` are then the birds simulated)
    ruled_out_by: str | None = None

    @property
    def holds(self) -> np.ndarray:
        return np.array([m.hold for m in self.members])

    @property
    def hold(self) -> float:
        return self.population.hold(self.holds)

    @property
    def peaks(self) -> np.ndarray:
        return np.array([m.peak for m in self.members])

    @property
    def peak(self) -> float:
        return float(self.peaks.max())

    @property
    def limiting(self) -> int:
        """The bird with the shortest hold."""
        return int(np.argmin(self.holds))

    @property
    def run(self) -> GraspRun:
        return self.members[self.limiting].run

    def excess(self, caps, tolerance: float = 0.0) -> float:
        """How far (N) the worst finger of any bird presses over its limit: the
        bird's cap (N) or the finger's fold force, whichever is lower, within
        ``tolerance`` (relative); inf where a bird is held to the end of its
        run or not carried on (a jam no force measures), or where its
        simulation ended early (a failed contact: nothing to judge)."""
        failed, jammed, worst = self.shortfall(caps, tolerance)
        return np.inf if failed or jammed else worst

    def shortfall(self, caps, tolerance: float = 0.0) -> tuple[int, int, float]:
        """How far the design is from keeping every rule, the worst first: how
        many birds' simulations ended early, how many birds are jammed (held
        to the end of the run or not carried on), and the largest force (N)
        of any finger of the other birds over its limit, as :meth:`excess`
        (-inf: no bird to judge)."""
        failed, jammed, worst = 0, 0, -np.inf
        for m, cap in self.with_caps(caps):
            s = m.run.summary
            if not s["ok"]:
                failed += 1
                continue
            jammed += bool(unmeasured_jams(s))
            limits = finger_limits(m.run.setup, cap)
            peaks = np.array([s["max_force_per_finger_N"][gf.name]
                              for gf in m.run.setup.grasper.fingers])
            worst = max(worst, float(np.max(peaks - limits * (1 + tolerance))))
        return failed, jammed, worst

    def with_caps(self, caps):
        """Each bird's evaluation with its cap (N; one number: every bird's)."""
        return zip(self.members, np.broadcast_to(np.asarray(caps, float), (len(self.members),)))

    def within(self, caps, tolerance: float = 0.0) -> bool:
        """Does every bird stay under its cap (N) and every finger under its
        fold force, within ``tolerance`` (relative), with no bird jammed?"""
        return self.excess(caps, tolerance) <= 0.0


def alone(run: Evaluated, member: Member) -> Scored:
    """One bird's simulation as a design scored for that bird alone."""
    return Scored(run.d, [run], Population((member,)))


def unmeasured_jams(summary: dict) -> list[str]:
    """A run's jams that no finger force measures (a bird held to the end of
    the run or not carried on); a finger past its fold force is judged by
    its force against :func:`~design.solvers.grasp.validity.finger_limits`."""
    return [reason for reason in summary["jam"] if not reason.startswith("finger ")]


@dataclass
class Outcome:
    """What the loop found, and how."""

    best: Scored
    #: the baseline as the loop simulated it (None: not simulated, a
    #: feasibility screen's answer)
    baseline: Scored | None
    #: each bird's cap (N)
    caps: np.ndarray
    iterations: list = field(default_factory=list)
    nlp: NLPResult | None = None
    #: each bird's fixed-design view of ``best`` (None: not yet, or it failed)
    finals: list | None = None
    #: the optimiser's hold for ``best`` and where it comes from (None: not yet)
    claim: tuple | None = None
    #: each bird's claim (hold (s), source)
    claims: list | None = None
    wall_time: float = 0.0
    #: where the loop's time went (its simulations, NLPs and views)
    profile: Profile = field(default_factory=Profile)
    #: a pattern search's settings and count (None: the trust-region loop)
    search: dict | None = None
    #: a pattern search's simulated designs, in order (each a Trial whose
    #: value is the design scored without its trajectories)
    trials: list = field(default_factory=list)

    @property
    def cap(self) -> float:
        """The first bird's cap (N): the cap of a single-bird problem."""
        return float(self.caps[0])

    @property
    def final(self) -> NLPResult | None:
        """The first bird's fixed-design view (a single-bird problem's)."""
        return self.finals[0] if self.finals else None

    @property
    def feasible(self) -> bool:
        return self.best.within(self.caps, CAP_TOLERANCE)

    @property
    def every_nlp_failed(self) -> bool:
        """Did every outer iteration's NLP fail (raise, or end on an Ipopt
        error), so that the loop never had a design to try?"""
        return bool(self.iterations) and all("error" in i for i in self.iterations)

    @property
    def errors(self) -> list[str]:
        """The distinct errors of the loop's NLPs and views, in order."""
        return list(dict.fromkeys(e for i in self.iterations
                                  for e in (i.get("error"), i.get("view_error")) if e))


def simulate(space: DesignSpace, d: np.ndarray, settings: LoopSettings,
             integrator: IntegratorSettings | None = None, cutoff: Cutoff | None = None
             ) -> Evaluated:
    """Simulate the scaled design ``d``, ended early where it shows it cannot
    beat ``cutoff``'s rival; its summary (hold, peak force) is computed
    here, once, so that a profile counts it with the simulation."""
    setup = space.setup(d)
    run = simulate_grasp(setup, integrator or settings.simulator, settings.contact_nodes,
                         watch=cutoff and cutoff.watch(setup))
    run.summary  # noqa: B018  (cached on the run)
    return Evaluated(np.asarray(d, float), run)


def score(population: Population, d: np.ndarray, settings: LoopSettings,
          integrator: IntegratorSettings | None = None, workers: int | None = 1) -> Scored:
    """Simulate the scaled design ``d`` for every bird of the population, the
    birds in ``workers`` processes (design/solvers/optimize/forked.py; None:
    one per core, at most two)."""
    return Scored(np.asarray(d, float),
                  forked_map(lambda m: simulate(m.space, d, settings, integrator),
                             population.members, workers), population)


#: forces over a limit (N) closer than this are equal when designs are compared
FORCE_BAND = 1e-3


def better(a: Scored, b: Scored, caps, tolerance: float = CAP_TOLERANCE,
           band: float = 1e-5) -> bool:
    """Is a better than b: feasible (every bird under its cap, every finger
    under its fold force, no jam; within ``tolerance``, by default the
    verification's, so that a baseline whose own peak is the cap is not
    judged by its rounding) beats infeasible, then the longer hold by more
    than ``band`` (s); among infeasible designs the one nearer to keeping
    the rules (:meth:`Scored.shortfall`): fewer failed simulations, then
    fewer jammed birds, then the smaller largest force over a limit, by more
    than 1 mN, so that a search from a design that jams a bird can move."""
    fa, fb = a.within(caps, tolerance), b.within(caps, tolerance)
    if fa != fb:
        return fa
    if fa:
        return a.hold > b.hold + band
    (fail_a, jam_a, over_a), (fail_b, jam_b, over_b) = a.shortfall(caps), b.shortfall(caps)
    if (fail_a, jam_a) != (fail_b, jam_b):
        return (fail_a, jam_a) < (fail_b, jam_b)
    return over_a < over_b - FORCE_BAND


def check_baseline(population: Population, baseline: Scored) -> None:
    """Refuse a baseline whose simulation of some bird ended early: no design
    loop can start from it.

    Raises
    ------
    ValueError
        Naming each such bird and why its run ended.
    """
    failed = [f"{m.name}: {e.run.summary['message']}" for m, e in
              zip(population.members, baseline.members) if not e.run.summary["ok"]]
    if failed:
        raise ValueError("the baseline's simulation ended early, so no design can start from "
                         "it: " + "; ".join(failed))


def population_of(space: DesignSpace | Population) -> Population:
    return space if isinstance(space, Population) else Population.of(space)


def optimise(space: DesignSpace | Population, cap, settings: LoopSettings,
             rules: Rules = Rules(), start: np.ndarray | None = None, progress=None,
             anchor: bool = True) -> Outcome:
    """Maximise the (population's) hold time under the cap (N; one per bird,
    or one for all) from ``start`` (scaled; the baseline by default). With
    ``anchor`` a start worse than the baseline gives way to it (a warm
    start); without, the loop goes from the start (a multistart's point)."""
    t0 = time.perf_counter()
    profile = Profile()
    say = progress or (lambda message: None)
    population = population_of(space)
    caps = np.broadcast_to(np.asarray(cap, float), (len(population.members),)).copy()
    d0 = population.space.scale(population.space.base_values)
    with profile.phase(SIMULATIONS):
        baseline = score(population, d0, settings)
    check_baseline(population, baseline)
    if start is None:
        best = baseline
    else:
        with profile.phase(SIMULATIONS):
            best = score(population, start, settings)
    if start is not None and anchor and better(baseline, best, caps):
        best = baseline
    out = Outcome(best, baseline, caps, profile=profile)
    radius, backed_off = settings.radius, caps.copy()
    # the last NLP and the design whose schedules it was built on: after a
    # rejected candidate the best design, hence the schedule, is the same, and
    # only the caps and the trust region change (DesignNLP.rebound; the same
    # solution as a new NLP's, without building the graph and the solver again)
    built: dict = {}

    def nlp_for(cap_nlp, box):
        if built.get("best") is best:
            return rebound(built["nlp"], cap_nlp, box)
        nlp = build_nlp(population, best, cap_nlp, settings, rules, box, progress)
        built.update(best=best, nlp=nlp)
        return nlp

    say(f"baseline: hold {baseline.hold:.4f} s, peak finger force {baseline.peak:.2f} N "
        f"(cap {caps_text(caps)})")
    for it in range(settings.outer_iterations):
        cap_nlp = np.minimum(backed_off, caps * (1 - settings.cap_margin / 2 ** it))
        lo = np.clip(best.d - radius, 0, 1)
        hi = np.clip(best.d + radius, 0, 1)
        say(f"outer iteration {it + 1}: trust region {radius:.3f}, NLP cap "
            f"{caps_text(cap_nlp)}")
        try:
            result = build_and_solve(profile, OPTIMISER, lambda: nlp_for(cap_nlp, (lo, hi)))
        except (RuntimeError, ValueError) as exc:
            out.iterations.append({"iteration": it + 1, "radius": radius, "error": str(exc)})
            say(f"outer iteration {it + 1}: NLP failed ({exc}); shrinking the trust region")
            radius /= 2
            if radius < settings.min_radius:
                break
            continue
        with profile.phase(SIMULATIONS):
            candidate = score(population, result.d, settings)
        accepted = better(candidate, best, caps)
        reproduced, views, view_error, claims = None, None, None, None
        if accepted:
            # stand only on designs whose simulation the optimiser's grid reproduces
            views, view_error = optimiser_views(population, candidate, settings, rules,
                                                progress, profile)
            claims = [optimiser_hold(view, result if len(views) == 1 else None)
                      for view in views]
            reproduced = all(reproduces(m, c[0]) for m, c in zip(candidate.members, claims))
            accepted = reproduced
        view = views[0] if views else None
        out.iterations.append({
            "iteration": it + 1, "radius": radius, "nlp_cap_N": caps_value(cap_nlp),
            "ipopt_status": result.status, "ipopt_iterations": result.iterations,
            "nlp_wall_time_s": result.wall_time, "nlp_hold_time_s": result.hold_time,
            "nlp_peak_force_N": result.peak_force, "nlp_violation": result.violation,
            "nlp_iteration_returned": result.iteration, "candidate_scaled": result.d.tolist(),
            "simulated_hold_time_s": candidate.hold,
            "simulated_peak_force_N": candidate.peak, "accepted": accepted,
            "grid_reproduces_simulation": reproduced, "view_error": view_error,
            "view": None if view is None else {
                "ipopt_status": view.status, "ipopt_iterations": view.iterations,
                "wall_time_s": view.wall_time, "hold_time_s": view.hold_time,
                "constraint_violation": view.violation if view.history else None,
                "iteration_returned": view.iteration},
            "nlp_size": result.size, "history": result.history,
            **({} if len(caps) == 1 else {
                "simulated_hold_times_s": candidate.holds.tolist(),
                "simulated_peak_forces_N": candidate.peaks.tolist()})})
        verdict_text = "accepted" if accepted else "rejected" if reproduced is None else \
            "rejected: the optimiser's grid does not reproduce its simulation"
        say(f"outer iteration {it + 1}: Ipopt {result.status} in {result.iterations} "
            f"iterations; NLP hold {result.hold_time:.4f} s, simulated {candidate.hold:.4f} s, "
            f"peak {candidate.peak:.2f} N -> {verdict_text}")
        # where the NLP kept its grid under a bird's cap but the simulation found
        # more between the stages or in a contact the schedule lacked: back off
        over = (candidate.peaks > caps) & (result.peaks <= cap_nlp * (1 + 1e-3))
        backed_off = np.where(over, cap_nlp * np.maximum(BACK_OFF, caps / candidate.peaks),
                              backed_off)
        if accepted:
            best, out.nlp, out.finals = candidate, result, views
            out.claims = claims
            out.claim = population.hold([c[0] for c in claims]), claims[0][1]
            radius = min(2 * radius, 0.5)
        else:
            radius /= 2
            if radius < settings.min_radius:
                break
    out.best = best
    out.wall_time = time.perf_counter() - t0
    return out


def build_nlp(population: Population, best: Scored, caps, settings: LoopSettings,
              rules: Rules, box, progress=None) -> DesignNLP:
    """The NLP around ``best``'s simulated schedules: the bird's own NLP for
    one bird, the population's for several."""
    step = settings.nlp.time_step
    if len(population.members) == 1:
        run = best.members[0].run
        return DesignNLP(population.space, schedule_of(run, step), run, float(caps[0]),
                         settings.nlp, rules, box, progress)
    runs = [m.run for m in best.members]
    return PopulationNLP(population, [schedule_of(r, step) for r in runs], runs, caps,
                         settings.nlp, rules, box, progress)


def rebound(nlp: DesignNLP, caps, box) -> DesignNLP:
    return nlp.rebound(caps if isinstance(nlp, PopulationNLP) else float(caps[0]), box)


def caps_value(caps: np.ndarray):
    """The caps (N) as result.json gives them: a number for one bird."""
    return float(caps[0]) if len(caps) == 1 else caps.tolist()


def caps_text(caps: np.ndarray) -> str:
    return f"{caps[0]:.2f} N" if len(caps) == 1 else \
        "[" + ", ".join(f"{c:.2f}" for c in caps) + "] N"


#: the optimiser's view counts when its largest constraint violation (m, m/s,
#: N, in the NLP's own units) is below this; Ipopt rarely reaches its own
#: tolerance on these non-smooth problems within the iteration limit, so the
#: agreement of the hold times (HOLD_TOLERANCE) is the real test
VIEW_FEASIBLE = 1e-2


def feasible(result: NLPResult | None) -> bool:
    return result is not None and bool(result.history) and result.violation < VIEW_FEASIBLE


def optimiser_hold(view: NLPResult | None, accepted: NLPResult | None) -> tuple[float, str]:
    """The hold time (s) the optimiser claims for its design, and where it
    comes from: the fixed-design NLP on the design's own schedule when it
    reached feasibility, else the NLP solution the design came from if that
    did; NaN (a claim that cannot pass verification) if neither."""
    if feasible(view):
        return view.hold_time, "fixed-design NLP on the design's own schedule"
    if feasible(accepted):
        return accepted.hold_time, "the NLP solve that produced the design"
    return float("nan"), "none: the fixed-design NLP did not converge"


def build_and_solve(profile: Profile, group: str, build) -> NLPResult:
    """``build()`` a DesignNLP and solve it, timed in ``profile`` under
    ``group``'s construction, Ipopt and read-back phases (also when either
    raises)."""
    nlp = None
    try:
        with profile.phase(f"{group}: {CONSTRUCTION}"):
            nlp = build()
        return nlp.solve()
    finally:
        profile.add_nlp(group, getattr(nlp, "timings", None))


def optimiser_view(space: DesignSpace, evaluated: Evaluated, settings: LoopSettings,
                   rules: Rules = Rules(), progress=None, profile: Profile | None = None
                   ) -> NLPResult:
    """The hold time on the optimiser's grid for a fixed design: the NLP with
    the design's bounds collapsed onto it, on its own simulated schedule
    (timed in ``profile`` as a fixed-design view).

    Raises
    ------
    RuntimeError, ValueError
        If the NLP cannot be built or evaluated there, or Ipopt ends on an
        error (:class:`~design.solvers.optimize.transcription.NLPFailed`).
    """
    # only durations and states move: allow more iterations, but stop one that
    # has stalled above feasibility (it would not reproduce the design anyway)
    nlp_settings = replace(settings.nlp, max_iter=max(settings.nlp.max_iter, VIEW_MAX_ITER),
                           stall_iterations=VIEW_STALL, stall_violation=VIEW_FEASIBLE)
    return build_and_solve(profile or Profile(), VIEWS, lambda: DesignNLP(
        space, schedule_of(evaluated.run, settings.nlp.time_step), evaluated.run, np.inf,
        nlp_settings, rules, (evaluated.d, evaluated.d), progress, objective="track"))


def optimiser_views(population: Population, scored: Scored, settings: LoopSettings,
                    rules: Rules = Rules(), progress=None, profile: Profile | None = None
                    ) -> tuple[list, str | None]:
    """Each bird's :func:`optimiser_view` of a design (None where it failed),
    and the failures' message (None if every view was built and solved)."""
    views, errors = [], []
    for member, evaluated in zip(population.members, scored.members):
        try:
            views.append(optimiser_view(member.space, evaluated, settings, rules, progress,
                                        profile))
        except (RuntimeError, ValueError) as exc:
            views.append(None)
            errors.append(str(exc) if len(scored.members) == 1 else f"{member.name}: {exc}")
    return views, ("the fixed-design NLP failed: " + "; ".join(errors)) if errors else None


def reproduces(evaluated: Evaluated, claimed: float) -> bool:
    """Does the optimiser's grid reproduce this simulated hold time?"""
    return bool(np.isfinite(claimed)) and abs(evaluated.hold - claimed) <= HOLD_TOLERANCE * claimed


def certify(space: DesignSpace | Population, outcome: Outcome, settings: LoopSettings,
            rules: Rules = Rules(), progress=None) -> tuple[float, str]:
    """The optimiser's hold time (s) for ``outcome.best`` and its source
    (``outcome.claims`` has each bird's); designs the loop accepted have it
    already, the start design gets its fixed-design NLPs now."""
    if outcome.claim is None:
        population = population_of(space)
        (progress or (lambda message: None))("the optimiser's view of the design on its "
                                             "own schedule")
        views, error = optimiser_views(population, outcome.best, settings, rules, progress,
                                       outcome.profile)
        outcome.finals = views
        outcome.claims = [
            (float("nan"), f"none: {error}") if view is None else
            optimiser_hold(view, outcome.nlp if len(views) == 1 else None) for view in views]
        outcome.claim = (population.hold([c[0] for c in outcome.claims]),
                         next((c[1] for c in outcome.claims if not np.isfinite(c[0])),
                              outcome.claims[0][1]))
    return outcome.claim


def verify(space: DesignSpace | Population, d: np.ndarray, settings: LoopSettings,
           factor: float = 4.0, workers: int | None = None,
           max_newton_solves: float | None = None) -> Scored:
    """Re-simulate every bird at ``factor`` times the optimiser's resolution:
    steps no longer than its grid step / factor, tolerances tightened by
    factor^4; the birds in ``workers`` processes (None: one per core, at
    most two); ``max_newton_solves``: the runs' budget of contact work
    (IntegratorSettings; None: none)."""
    s = settings.simulator
    fine = replace(s.finer(factor), max_step=min(s.max_step, settings.nlp.time_step) / factor,
                   max_newton_solves=max_newton_solves)
    return score(population_of(space), d, settings, fine, workers)


def verdict(nlp_hold: float, verified: Evaluated, cap: float) -> dict:
    """The verification table's numbers and pass/fail: the hold reproduced,
    the peak under the cap, and no jam (design/solvers/grasp/simulation.py)."""
    hold_error = abs(verified.hold - nlp_hold) / max(nlp_hold, 1e-12)
    s = verified.run.summary
    passed = hold_error <= HOLD_TOLERANCE and verified.peak <= cap * (1 + CAP_TOLERANCE) \
        and not s["jammed"] and s["ok"]
    return {"finger_model": s["finger_model"],
            "hold_time_s": verified.hold, "hold_windows": s["hold_windows"],
            "max_finger_force_N": verified.peak,
            "max_finger_force_finger": s["max_finger_force_finger"],
            "max_finger_force_time_s": s["max_finger_force_time_s"],
            "cap_N": cap, "optimiser_hold_time_s": nlp_hold,
            "hold_time_relative_difference": hold_error,
            "hold_tolerance": HOLD_TOLERANCE, "cap_tolerance": CAP_TOLERANCE,
            "model_warnings": validity_problems(s["validity"]),
            "jam": s["jam"], "simulation_ok": s["ok"], "simulation_message": s["message"],
            "passed": bool(passed)}


def population_verdict(population: Population, claims: list, verified: Scored, caps) -> dict:
    """:func:`verdict` for every bird (``birds``); the top-level numbers are
    the population's: its hold, the worst hold disagreement, the bird
    closest to (or furthest over) its cap. One bird: that bird's verdict."""
    if len(population.members) == 1:
        return verdict(claims[0][0], verified, float(caps[0]))
    birds = [{"bird": m.name, "weight": float(w), **verdict(c[0], e, float(cap))}
             for m, w, c, e, cap in zip(population.members, population.weights, claims,
                                        verified.members, caps)]
    k = int(np.argmax(verified.peaks / np.asarray(caps)))
    tight, limiting = birds[k], birds[verified.limiting]
    return {"aggregate": population.aggregate, "finger_model": limiting["finger_model"],
            "hold_time_s": verified.hold,
            "hold_windows": limiting["hold_windows"], "limiting_bird": limiting["bird"],
            "max_finger_force_N": tight["max_finger_force_N"],
            "max_finger_force_finger": tight["max_finger_force_finger"],
            "max_finger_force_time_s": tight["max_finger_force_time_s"],
            "max_finger_force_bird": tight["bird"], "cap_N": tight["cap_N"],
            "optimiser_hold_time_s": population.hold([c[0] for c in claims]),
            "hold_time_relative_difference": max(b["hold_time_relative_difference"]
                                                 for b in birds),
            "hold_tolerance": HOLD_TOLERANCE, "cap_tolerance": CAP_TOLERANCE,
            "model_warnings": list(dict.fromkeys(f"{b['bird']}: {w}" for b in birds
                                                 for w in b["model_warnings"])),
            "passed": all(b["passed"] for b in birds), "birds": birds}
