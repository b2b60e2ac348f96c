"""The pattern search's lattice coordinate search (design/solvers/optimize/
pattern_search.py) on analytic objectives: it finds the lattice optimum,
keeps its budget and the allowed region, and its path does not move when
the objective and the start move by round-off."""

import os
from collections import namedtuple
from dataclasses import replace
from types import SimpleNamespace

import numpy as np
import pytest

from design.solvers.optimize import pattern_search, trust_region
from design.solvers.optimize.multistart import starting_designs
from design.solvers.optimize.pattern_search import (FIRST_STEP, LATTICE, SURVEY_SEED, Pairs,
                                                    compass, survey)

UNIT = 1 / LATTICE
from design.solvers.optimize.scenes import Scenes
from design.solvers.optimize.population import Member, Population
from design.solvers.optimize.trust_region import Evaluated
from design.solvers.optimize.variables import DesignSpace, Variable
from tests.design_cases import short_setup

CENTRE = np.array([0.71, 0.23, 0.5, 0.9])
WEIGHT = np.array([1.0, 3.0, 0.5, 2.0])


def quadratic(d, noise: float = 0.0):
    """A concave objective, maximal at CENTRE, with a relative error of
    ``noise`` that depends on d's bits (round-off of another machine)."""
    value = -float(np.sum(WEIGHT * (np.asarray(d) - CENTRE) ** 2))
    jitter = np.sin(1e4 * np.dot(d, [1.0, 2.0, 3.0, 4.0]))
    return value * (1 + noise * jitter)


def run(d0, noise=0.0, band=1e-6, **kw):
    def evaluate_many(designs, incumbent, ahead):
        return [quadratic(d, noise) for d in designs]
    return compass(evaluate_many, np.asarray(d0, float), quadratic(d0, noise),
                   lambda a, b: a > b + band, **kw)


def test_the_search_ends_at_the_lattice_optimum():
    """Every coordinate of the answer is within half a lattice unit of the
    centre (the objective is separable, so the best lattice point rounds each
    coordinate), and no neighbour one unit away is better."""
    d0 = np.full(4, 0.5)
    found = run(d0)
    assert found.lattice_optimum
    assert np.all(np.abs(found.d - CENTRE) <= UNIT / 2 + 1e-12)
    for i in range(4):
        for s in (1, -1):
            neighbour = np.clip(found.d + s * UNIT * np.eye(4)[i], 0, 1)
            assert quadratic(neighbour) <= found.value + 1e-12


def test_round_off_does_not_move_the_path(monkeypatch):
    """A start moved by 1e-9 (relative) and objective values wrong by up to
    1e-9 (relative): the same moves, the same answer to 1e-9. The first
    coordinate's optimum lies half-way between two lattice points, which
    tie: without the band the round-off picks one of them, with it neither
    displaces the other."""
    monkeypatch.setattr("tests.test_pattern_search.CENTRE",
                        np.array([0.5 + 3.5 * UNIT, 0.23, 0.5, 0.9]))
    d0 = np.array([0.5, 0.5, 0.5, 0.3])

    def moves(found):
        return [(t.variable, t.units, t.move, t.taken) for t in found.trials]
    for band, same in ((1e-6, True), (0.0, False)):
        a = run(d0, band=band)
        b = run(d0 * (1 + 1e-9), noise=1e-9, band=band)
        assert (moves(a) == moves(b)) == same
        assert (np.max(np.abs(a.d - b.d)) < 1e-8) == same


def test_the_band_refuses_a_gain_smaller_than_itself():
    """With a band wider than any one-unit gain near the optimum the search
    stops on a coarser point; the band only ever refuses moves."""
    d0 = np.full(4, 0.5)
    fine, coarse = run(d0), run(d0, band=1e-3)
    assert coarse.value <= fine.value
    assert not np.allclose(coarse.d, fine.d)
    steps = [t for t in coarse.trials if t.taken]
    values = [quadratic(d0)] + [t.value for t in steps]
    assert all(later > earlier + 1e-3 for earlier, later in zip(values, values[1:]))


def test_the_budget_and_the_allowed_region_are_kept():
    """Never more evaluations than the budget (the start counts), never a
    point outside the allowed region, and the answer inside it."""
    d0 = np.full(4, 0.5)
    small = run(d0, max_evaluations=5)
    assert len(small.trials) + 1 <= 5 and not small.lattice_optimum
    full = run(d0)
    short = run(d0, max_evaluations=len(full.trials))      # one short of the whole search
    assert full.lattice_optimum and not short.lattice_optimum

    def allowed(d):
        return d[0] + d[3] <= 1.2
    kept = run(d0, allowed=allowed)
    assert all(allowed(t.d) for t in kept.trials) and allowed(kept.d)
    assert kept.d[0] + kept.d[3] == pytest.approx(1.2, abs=2 * UNIT)


def test_steps_halve_from_an_eighth_to_one_lattice_unit_and_stop_at_the_box():
    d0 = np.array([0.95, 0.5, 0.5, 0.5])
    found = run(d0)
    steps = sorted({abs(t.units) for t in found.trials}, reverse=True)
    assert steps == [LATTICE // FIRST_STEP >> n for n in range(len(steps))] and steps[-1] == 1
    assert np.all((found.d >= 0) & (found.d <= 1))


def test_a_coarser_lattice_takes_the_finer_ones_steps_and_stops_sooner():
    """On 1/32 of each box the search makes the 1/64 search's first trials
    (the same points in the same order, the same moves) and ends on the
    point the finer search stood at when its step first fell to 1/64: a
    lattice optimum of its own, one unit short of the finer answer."""
    d0 = np.full(4, 0.5)
    fine, coarse = run(d0), run(d0, lattice=32)
    n = len(coarse.trials)
    assert 0 < n < len(fine.trials)
    assert all(np.array_equal(a.d, b.d) and a.taken == b.taken and 2 * a.units == b.units
               for a, b in zip(coarse.trials, fine.trials[:n]))
    assert abs(fine.trials[n].units) == 1 and all(abs(t.units) > 1 for t in fine.trials[:n])
    assert coarse.lattice_optimum and np.all(np.abs(coarse.d - CENTRE) <= 1 / 64 + 1e-12)
    assert coarse.value <= fine.value


#: a stand-in finger, fold force, birds' centres and hold weights for
#: :func:`_bird_run`: bird b's hold is ``HOLD - sum(w (d - centre_b)^2)``,
#: its one finger's force ``FORCE * (1 + d[0] - d[1] / 2) * (1 + b / 4)``
_SETUP = SimpleNamespace(grasper=SimpleNamespace(fingers=[SimpleNamespace(name="1a")]))
CENTRES = np.array([[0.6, 0.3, 0.5, 0.8], [0.7, 0.25, 0.4, 0.9], [0.75, 0.2, 0.55, 0.95]])
HOLD, FORCE = 1.0, 10.0


def _bird_run(space, d, settings, integrator, cutoff=None):
    """A stand-in for one bird's simulation (``space`` is the bird's index):
    its hold (s), its one finger's force (N) and the process that ran it;
    with a ``cutoff`` it cannot beat, a run stopped at its start (hold and
    force 0) that says so and keeps the cutoff."""
    b, d = space, np.asarray(d, float)
    return _stand_in(d, HOLD - float(np.sum(WEIGHT * (d - CENTRES[b]) ** 2)),
                     FORCE * (1 + d[0] - d[1] / 2) * (1 + b / 4), cutoff)


def _stand_in(d, hold, force, cutoff):
    stopped = cutoff is not None and (hold <= cutoff.hold or force > cutoff.cap)
    if stopped:
        hold, force = 0.0, 0.0
    return Evaluated(d, SimpleNamespace(
        setup=_SETUP, trajectory=None, windows=None,
        summary={"ok": True, "jam": [], "hold_time_s": hold, "max_finger_force_N": force,
                 "max_force_per_finger_N": {"1a": force}, "pid": os.getpid(),
                 "stopped": "cannot beat" if stopped else None, "cutoff": cutoff}))


@pytest.fixture
def birds(monkeypatch):
    """Three stand-in birds (:func:`_bird_run`) whose fingers fold far above any cap."""
    monkeypatch.setattr(pattern_search, "simulate", _bird_run)
    monkeypatch.setattr(trust_region, "finger_limits", lambda setup, cap: np.array([cap]))
    return Population(tuple(Member(f"bird-{b}", b) for b in range(3)))


def one_bird(birds, monkeypatch, run):
    """The first stand-in bird alone, its simulation ``run``, and how the
    search judges its designs under a 13 N cap: (population, beats, rivals)."""
    monkeypatch.setattr(pattern_search, "simulate", run)
    bird = replace(birds, members=birds.members[:1])
    return (bird, *pattern_search.judges(bird, np.full(1, 13.0),
                                         SimpleNamespace(objective="hold", min_hold=None)))


def test_pairs_on_two_processes_give_what_one_gives(birds):
    """The birds of the designs a search evaluates together go to two forked
    processes, in order, with the values one process computes: each bird's
    own simulation of its design."""
    designs = [np.full(4, x) for x in (0.1, 0.4, 0.7, 0.9)]
    with Pairs(birds, None, None, workers=1) as one, Pairs(birds, None, None, workers=2) as two:
        here, there = one.score(designs), two.score(designs)
    assert [v.holds.tolist() for v in here] == [v.holds.tolist() for v in there] == [
        [_bird_run(b, d, None, None).hold for b in range(3)] for d in designs]
    assert {m.run.summary["pid"] for v in here for m in v.members} == {os.getpid()}
    pids = {m.run.summary["pid"] for v in there for m in v.members}
    assert two.processes == 2 and os.getpid() not in pids
    assert one.simulations == two.simulations == 12


@pytest.mark.parametrize("size", [3, 1])
def test_a_search_that_rules_candidates_out_takes_the_same_steps(birds, size, monkeypatch):
    """The worst hold of three birds, or one bird's hold, under a cap that
    binds: the search with every run whole, and the search that ends a run
    where it shows that its candidate cannot beat the incumbent (and
    simulates no more of its birds), take the same steps to the same
    design, the second on fewer simulations, on one process or two; every
    ruled-out candidate's whole runs indeed cannot beat the incumbent it was
    judged against, and a stopped run was stopped against the hold of a
    design the search stood at."""
    birds = replace(birds, members=birds.members[:size])
    # a core free for runs ahead, whatever else the machine runs
    monkeypatch.setattr("design.solvers.optimize.ahead.others_running", lambda: 0)
    caps = np.full(size, 13.0)
    settings = SimpleNamespace(objective="hold", min_hold=None)
    beats, rivals = pattern_search.judges(birds, caps, settings)
    d0 = np.full(4, 0.5)

    def searched(rivals, workers):
        with Pairs(birds, None, None, workers, rivals) as pool:
            start, = pool.score([d0])
            found = compass(pool.score, d0, start, beats, max_evaluations=40)
        return found, pool, start

    (every, every_pool, start), (lazy, lazy_pool, _), (lazy2, pool2, _) = (
        searched(None, 1), searched(rivals, 1), searched(rivals, 2))
    n_every, n_lazy = every_pool.simulations, lazy_pool.simulations
    moves = [[(t.variable, t.units, t.move, t.taken) for t in f.trials] for f in
             (every, lazy, lazy2)]
    assert moves[0] == moves[1] == moves[2]
    # on two processes, runs started ahead (the next poll's) change nothing recorded
    assert pool2.ran_ahead["used"] > 0 and pool2.simulations == n_lazy
    assert [(t.value.holds.tolist(), t.value.ruled_out_by) for t in lazy.trials] == \
        [(t.value.holds.tolist(), t.value.ruled_out_by) for t in lazy2.trials]
    assert np.array_equal(every.d, lazy.d) and every.value.hold == lazy.value.hold
    assert every.value.within(caps) and every.value.hold > start.hold + 0.01
    ruled = [t for t in lazy.trials if t.value.ruled_out_by]
    assert ruled and n_lazy <= n_every - (size - 1) * len(ruled)
    # a ruled-out candidate carries the birds it simulated, each its own run
    stood_at = [start.hold] + [t.value.hold for t in lazy.trials if t.taken]
    for t in ruled:
        members = t.value.population.members
        assert t.value.ruled_out_by in [m.name for m in members]
        for m, e in zip(members, t.value.members):
            cutoff = e.run.summary["cutoff"]
            assert cutoff.hold in stood_at and cutoff.cap == 13.0
            assert e.hold == _bird_run(m.space, t.d, None, None, cutoff).hold
    assert any(e.run.summary["stopped"] for t in ruled for e in t.value.members)
    complete = {tuple(t.d): t.value for t in every.trials}
    assert not any(beats(complete[tuple(t.d)], incumbent)
                   for t, incumbent in judged_against(lazy, start))


def test_a_candidate_ruled_out_does_not_win_a_poll_its_whole_run_would_tie(birds, monkeypatch):
    """A poll whose up step holds 0.6 band longer than the incumbent and
    whose down step 1.2 band longer: on whole runs the up step wins the
    poll (the two within the band: up on a tie) and, not beating the
    incumbent, no move is taken. A candidate is ruled out only by a hold no
    longer than the incumbent's, not by one within the band of it, so the
    search that rules candidates out takes no move either."""
    band, base = pattern_search.HOLD_BAND, 0.5
    holds = {0.5 + 1 / FIRST_STEP: base + 0.6 * band,
             0.5 - 1 / FIRST_STEP: base + 1.2 * band}

    def tie_run(space, d, settings, integrator, cutoff=None):
        d = np.asarray(d, float)
        on_axis = np.all(d[1:] == 0.5)
        hold = holds.get(float(d[0]), base - 0.01) if on_axis else base - 0.01
        return _stand_in(d, base if np.all(d == 0.5) else hold, FORCE, cutoff)
    bird, beats, rivals = one_bird(birds, monkeypatch, tie_run)
    d0 = np.full(4, 0.5)

    def searched(rivals):
        with Pairs(bird, None, None, 1, rivals) as pool:
            start, = pool.score([d0])
            return compass(pool.score, d0, start, beats, max_evaluations=12)

    whole, ruling = searched(None), searched(rivals)
    assert [t.taken for t in whole.trials] == [t.taken for t in ruling.trials]
    assert not any(t.taken for t in whole.trials)
    assert [t.value.hold for t in ruling.trials[:2]] == [base + 0.6 * band, base + 1.2 * band]


def test_a_run_started_ahead_against_another_incumbent_is_not_used(birds, monkeypatch):
    """A run started ahead is used only by a call that asks for the same
    design against the same incumbent: asked for against another, the
    design is simulated again, against that one, and the run ahead is
    dropped."""
    bird, _, rivals = one_bird(birds, monkeypatch, _bird_run)
    monkeypatch.setattr("design.solvers.optimize.ahead.others_running", lambda: 0)
    d = np.full(4, 0.6)
    with Pairs(bird, None, None, 2, rivals) as pool:
        first, second = pool.score([np.full(4, 0.5), np.full(4, 0.55)])
        pool.score([np.full(4, 0.4)], first, ahead=[d])
        asked, = pool.score([d], second)
    assert first.hold != second.hold
    assert asked.members[0].run.summary["cutoff"].hold == second.hold
    assert pool.ran_ahead == {"used": 0, "unused": 1}


def judged_against(found, start):
    """Each ruled-out trial with an incumbent that it cannot beat: the last
    step taken before it (the start where none), which is the one it was
    judged against or a better one."""
    incumbent, out = start, []
    for t in found.trials:
        if t.value.ruled_out_by:
            out.append((t, incumbent))
        if t.taken:
            incumbent = t.value
    return out


def test_a_baseline_whose_simulation_ended_early_is_refused_naming_the_bird():
    """Both design loops start with check_baseline: a bird whose baseline run
    ended early (a contact that could not be solved) leaves no design to
    start from; the error names that bird and why, and no other."""
    from types import SimpleNamespace as Run

    from design.solvers.optimize.trust_region import check_baseline
    birds = Run(members=[Run(name="small"), Run(name="large")])
    ran = Run(members=[Run(run=Run(summary={"ok": True, "message": "finished"})),
                       Run(run=Run(summary={"ok": False,
                                            "message": "finger 5a failed at 0.91 s"}))])
    with pytest.raises(ValueError, match=r"no design can start from it: large: finger 5a "
                                         r"failed at 0\.91 s$"):
        check_baseline(birds, ran)
    ran.members[1].run.summary["ok"] = True
    check_baseline(birds, ran)


def test_the_search_ends_at_the_first_step_whose_value_is_enough():
    """A feasibility screen asks for a good enough design, not the best: the
    search stops at the first step taken whose value is enough (no lattice
    optimum claimed), and at once where the start is enough."""
    d0 = np.full(4, 0.5)
    whole = run(d0)
    level = -0.05
    assert quadratic(d0) < level < whole.value
    found = run(d0, enough=lambda v: v >= level)
    taken = [t for t in found.trials if t.taken]
    assert found.value >= level and not found.lattice_optimum
    # nothing simulated after that step but its extension pair's other point
    last = next(n for n, t in enumerate(found.trials) if t is taken[-1])
    assert taken[-1].value == found.value and last >= len(found.trials) - 2
    assert all(t.value < level for t in taken[:-1])
    assert len(found.trials) < len(whole.trials)
    at_once = run(d0, enough=lambda v: True)
    assert at_once.trials == [] and np.array_equal(at_once.d, d0)


def test_a_design_whose_scene_was_scored_takes_its_score_and_the_search_its_steps(
        birds, monkeypatch):
    """A bird whose variable 0 stops acting once variable 1 is at the top of
    its box (as a belt's start does once its final speed is its speed): a
    search through :class:`Scenes` takes the same steps, with the same
    values, to the same design as one that simulates every design; the
    designs it did not simulate are those whose scene it had, and it
    simulates that many fewer."""
    centre = np.array([0.6, 1.0, 0.5, 0.8])

    def acting(d):
        d = np.array(d, float)
        if d[1] == 1.0:
            d[0] = centre[0]
        return d

    def bird_run(space, d, settings, integrator, cutoff=None):
        return _stand_in(np.asarray(d, float),
                         HOLD - float(np.sum(WEIGHT * (acting(d) - centre) ** 2)), FORCE, cutoff)
    bird, beats, _ = one_bird(birds, monkeypatch, bird_run)
    d0 = np.full(4, 0.5)

    def searched(once: bool):
        with Pairs(bird, None, None, 1) as pool:
            scenes = Scenes(pool.score, lambda d: tuple(acting(d))) if once else None
            score = scenes.score if once else pool.score
            start, = score([d0])
            return compass(score, d0, start, beats, max_evaluations=60), pool, scenes
    (every, every_pool, _), (once, once_pool, scenes) = searched(False), searched(True)
    assert [(t.variable, t.units, t.move, t.taken, t.value.hold) for t in every.trials] == \
        [(t.variable, t.units, t.move, t.taken, t.value.hold) for t in once.trials]
    assert np.array_equal(every.d, once.d) and once.d[1] == 1.0
    repeats = scenes.repeats
    assert len(repeats) >= 3
    assert once_pool.simulations == every_pool.simulations - len(repeats)
    for t in once.trials:
        if t.d.tobytes() in repeats:
            assert t.d[1] == 1.0 and np.array_equal(t.value.d, t.d)
            assert t.value.hold == bird_run(None, t.d, None, None).hold


def test_a_belt_that_does_not_slow_has_no_start_or_rate_to_act():
    """Where the belt's final speed is its speed (to round-off), designs that
    differ only in its start and rate set up one belt, at its speed all run
    long, and have one scene key; where it slows, they do not."""
    setup = short_setup()
    v = setup.conveyor.speed
    space = DesignSpace(setup, [Variable("conveyor.start_time", 0.0, 1.4, 0.0),
                                Variable("conveyor.final_speed", v / 2, v, v),
                                Variable("conveyor.rate", 0.5, 3.0, 2.0)])
    steady = [np.array([0.2, 1.0, 0.3]), np.array([0.7, 1 - 1e-14, 0.9])]
    a, b = (space.setup(d).conveyor for d in steady)
    assert a == b and space.scene_key(steady[0]) == space.scene_key(steady[1])
    assert all(a.velocity(t, a.start_time) == (v, 0.0) for t in (0.0, 0.3, 1.0, 1.5))
    slowing = [np.array([0.2, 0.99, 0.3]), np.array([0.7, 0.99, 0.3]),
               np.array([0.2, 0.99, 0.9])]
    assert len({space.scene_key(d) for d in slowing}) == 3
    c = space.setup(slowing[1]).conveyor
    assert c.velocity(1.3, c.start_time)[0] < v


#: a surveyed design's value: its hold (s) and whether it keeps its limits
Held = namedtuple("Held", "hold within", defaults=(True,))


def held_beats(a: Held, b: Held) -> bool:
    """The search's rule on :class:`Held` values: keeping the limits first,
    then a hold longer by more than a band."""
    if a.within != b.within:
        return a.within
    return a.hold > b.hold + 1e-6


def two_hills(d):
    """A narrow low hill at the box's centre and a wide higher one near a
    corner: a coordinate search from the centre ends on the low one."""
    d = np.asarray(d, float)
    near, far = np.full(4, 0.5), np.array([0.85, 0.15, 0.8, 0.2])
    return max(1.0 - 8 * float(np.sum((d - near) ** 2)), 1.5 - 2 * float(np.sum((d - far) ** 2)))


def test_the_survey_starts_the_search_on_the_higher_hill():
    """The survey simulates the first points of the multistart's Sobol
    sequence together (its eight points begin with the multistart's seven)
    and the search starts from the best that beats the baseline: from the
    centre alone the search ends on the low hill, from the survey's best on
    the high one."""
    d0 = np.full(4, 0.5)
    asked = []

    def score(designs, incumbent):
        asked.append((len(designs), incumbent))
        return [Held(two_hills(d)) for d in designs]
    trials = survey(score, d0, Held(two_hills(d0)), held_beats, lambda d: True, 8)
    points = starting_designs(d0, 9, SURVEY_SEED)[1:]
    assert asked == [(8, Held(two_hills(d0)))]
    assert all(np.array_equal(t.d, p) for t, p in zip(trials, points)) and len(trials) == 8
    assert all(np.array_equal(a, b) for a, b in zip(points, starting_designs(d0, 8, 0)[1:]))
    taken = [t for t in trials if t.taken]
    assert len(taken) == 1 and taken[0].value.hold == max(t.value.hold for t in trials)
    assert all(t.move == "survey" and t.variable is None for t in trials)

    def search_from(start):
        return compass(lambda ds, incumbent, ahead: [two_hills(d) for d in ds], start,
                       two_hills(start), lambda a, b: a > b + 1e-6)
    alone, surveyed = search_from(d0), search_from(taken[0].d)
    assert alone.value == pytest.approx(1.0, abs=1e-3)
    assert surveyed.value == pytest.approx(1.5, abs=1e-3)


def test_the_survey_takes_the_first_of_equals_and_nothing_that_does_not_beat():
    """Two surveyed points equal within the band: the first is taken; no
    point beating the baseline: none is, and the search starts from the
    baseline; a point breaking a design rule is not simulated."""
    d0 = np.full(4, 0.5)
    values = [Held(h) for h in (0.2, 0.7, 0.3, 0.7 + 1e-9, 0.1, 0.0, 0.6, 0.5)]

    def score(designs, incumbent):
        return values[:len(designs)]
    trials = survey(score, d0, Held(0.4), held_beats, lambda d: True, 8)
    assert [t.taken for t in trials] == [n == 1 for n in range(8)]
    assert not any(t.taken for t in survey(score, d0, Held(0.7), held_beats, lambda d: True, 8))
    points = starting_designs(d0, 9, SURVEY_SEED)[1:]
    kept = survey(score, d0, Held(0.4), held_beats, lambda d: d[0] < 0.5, 8)
    assert [t.d.tolist() for t in kept] == [p.tolist() for p in points if p[0] < 0.5]


def test_the_survey_does_not_start_from_a_design_that_keeps_the_limits_by_holding_less():
    """A baseline over its limits (a jam) holding 0.48 s: a surveyed design
    that keeps the limits by holding nothing beats it (the search's rule)
    but is no start; one within the limits holding longer is, even after a
    nearer-to-the-limits one that holds longer still."""
    baseline = Held(0.48, False)

    def taken(values):
        trials = survey(lambda designs, incumbent: values[:len(designs)], np.full(4, 0.5),
                        baseline, held_beats, lambda d: True, len(values))
        return [t.taken for t in trials]
    idle, over, held = Held(0.0), Held(0.6, False), Held(0.55)
    assert taken([idle, idle]) == [False, False]
    assert taken([idle, over, held, idle]) == [False, False, True, False]
    assert taken([idle, over]) == [False, True]
