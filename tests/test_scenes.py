"""A search's design whose run would be one already simulated
(design/solvers/optimize/scenes.py): a design that moves only fingers the
current design's run never reached has that run, record for record, and
the search scores it so without simulating it."""

import copy
from dataclasses import replace

import numpy as np
import pytest

from design.solvers.grasp.fingers import clear_at
from design.solvers.grasp.simulation import SPATIAL_NODES, simulate_grasp
from design.solvers.optimize import pattern_search
from design.solvers.optimize.multistart import starting_designs
from design.solvers.optimize.pattern_search import LATTICE, search
from design.solvers.optimize.population import Population
from design.solvers.optimize.scenes import Scenes, same_run
from design.solvers.optimize.trust_region import (LOOP_SIMULATOR, Evaluated, LoopSettings,
                                                   Scored)
from tests.test_spatial_nlp import placed_space


@pytest.fixture(scope="module")
def placed():
    """The placed mean bird's first 0.1 s with the spatial finger at the
    search's tolerance (0.5 s CPU): fingers 1a, 2a, 4a and 5a reach it
    (5a's tip on the belt); the fingers 3 stay clear."""
    space = placed_space(0.1)
    d0 = space.scale(space.base_values)
    run = simulate_grasp(space.setup(d0), LOOP_SIMULATOR, SPATIAL_NODES)
    population = Population.of(space)
    return space, population, Scored(d0, [Evaluated(d0, run)], population)


def moved(space, d, name: str, units: int) -> np.ndarray:
    """``d`` with variable ``name`` moved by ``units`` lattice units."""
    out = np.array(d, float)
    out[[v.name for v in space.variables].index(name)] += units / LATTICE
    return out


def test_a_finger_clear_at_every_instant_the_run_looked_was_never_reached(placed):
    """:func:`clear_at` agrees with the run's own test of which fingers to
    solve: no finger it finds clear at all the run's probes was ever
    reached, and it finds some clear (the test is not empty)."""
    space, _, reference = placed
    run, setup = reference.run, space.baseline
    names = [gf.name for gf in setup.grasper.fingers]
    clear = {i for i in range(len(names))
             if clear_at(setup.grasper, setup.bird, setup.drum_speed, [i], run.probes)}
    assert {names[i] for i in run.reached} == {"1a", "2a", "4a", "5a"}
    assert not clear & run.reached
    assert {"3a", "3b", "3c"} <= {names[i] for i in clear}
    assert len(run.probes) > 3 * len(run.trajectory.records)


def test_a_design_that_moves_only_unreached_fingers_has_the_same_run(placed):
    """Fingers 3 turned by one lattice unit: the design's own simulation is
    the reference's record for record (times and states to the bit), and
    :class:`Scenes` scores it as the reference without simulating it.
    Finger 4 turned (4a pressed the bird) or the lower group stiffened
    (5a rested on the belt): not the same run."""
    space, population, reference = placed
    d = moved(space, reference.d, "fingers.3.angle", 1)
    assert same_run(population, d, reference)
    own = simulate_grasp(space.setup(d), LOOP_SIMULATOR, SPATIAL_NODES)
    ref = reference.run
    assert [r.t for r in own.trajectory.records] == [r.t for r in ref.trajectory.records]
    assert all(np.array_equal(a.y, b.y) for a, b in zip(own.trajectory.records,
                                                        ref.trajectory.records))
    assert own.summary["max_force_per_finger_N"] == ref.summary["max_force_per_finger_N"]
    assert own.summary["hold_windows"] == ref.summary["hold_windows"]

    simulated = []
    scenes = Scenes(lambda designs, incumbent, ahead: simulated.extend(designs),
                    space.scene_key, lambda d, incumbent: same_run(population, d, incumbent))
    scored, = scenes.score([d], reference)
    assert simulated == [] and scenes.repeated(d)
    assert scored.hold == reference.hold and np.array_equal(scored.d, d)
    for other in (moved(space, reference.d, "fingers.4.angle", 1),
                  moved(space, reference.d, "groups.lower.stiffness_scale", 1),
                  moved(space, reference.d, "conveyor.rate", 1)):
        assert not same_run(population, other, reference)


def test_the_search_walks_the_lattice_its_settings_name(placed, monkeypatch):
    """Every design run as the baseline (no step beats it): on a lattice of
    8 units the search polls each variable at 1/8 of its box and ends, a
    lattice optimum; on the default lattice it halves that step down to
    1/64 before it ends."""
    space, population, reference = placed
    monkeypatch.setattr(pattern_search, "simulate", lambda space, d, *args, **kwargs:
                        Evaluated(np.asarray(d, float), reference.members[0].run))
    for lattice in (8, LATTICE):
        settings = replace(LoopSettings(), method="pattern", lattice=lattice,
                           simulator=LOOP_SIMULATOR)
        out = search(population, reference.peak + 1.0, settings, workers=1)
        radii = sorted({h["radius"] for h in out.iterations}, reverse=True)
        assert radii == [1 / n for n in (8, 16, 32, 64) if n <= lattice]
        assert out.search["lattice"] == 1 / lattice and out.search["lattice_optimum"]


def test_a_survey_starts_the_search_at_its_best_point_within_the_budget(placed, monkeypatch):
    """A hold that grows towards the point of the box opposite the
    baseline: the search first simulates the survey's eight Sobol points,
    then polls around the best of them, the survey counted in its budget;
    started from a given design it surveys nothing."""
    space, population, reference = placed
    d0 = space.scale(space.base_values)
    corner = 1 - d0

    def run(space, d, *args, **kwargs):
        d = np.asarray(d, float)
        held = copy.copy(reference.members[0].run)
        held.__dict__["summary"] = {**held.summary, "jam": [], "hold_time_s":
                                    reference.hold + 0.1 - 0.01 * float(np.sum((d - corner) ** 2))}
        return Evaluated(d, held)
    monkeypatch.setattr(pattern_search, "simulate", run)
    settings = replace(LoopSettings(), method="pattern", lattice=8, survey=8, max_simulations=20,
                       simulator=LOOP_SIMULATOR)
    out = search(population, reference.peak + 1.0, settings, workers=1)
    points = starting_designs(d0, 9, 0)[1:]
    rows = out.iterations
    assert [h["move"] for h in rows[:8]] == ["survey"] * 8
    assert all(np.array_equal(h["candidate_scaled"], p) for h, p in zip(rows, points))
    holds = [h["simulated_hold_time_s"] for h in rows[:8]]
    best = int(np.argmax(holds))
    assert [h["accepted"] for h in rows[:8]] == [n == best for n in range(8)]
    first_poll = np.array(rows[8]["candidate_scaled"]) - points[best]
    assert np.count_nonzero(np.abs(first_poll) > 1e-12) == 1
    assert np.max(np.abs(first_poll)) == pytest.approx(1 / 8)
    assert out.search["survey"] == 8 and out.search["simulations"] == 20
    assert not out.search["lattice_optimum"] and out.best.hold > holds[best]
    started = search(population, reference.peak + 1.0, settings, start=d0, workers=1)
    assert "survey" not in {h["move"] for h in started.iterations}
    assert started.search["survey"] == 0
