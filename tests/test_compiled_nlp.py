"""The design NLP's reuse (design/solvers/optimize/transcription.py): an NLP
solved again with another cap and trust region (DesignNLP.rebound, what the
design loop does after a rejected candidate) gives to the last bit what a
new NLP with those bounds gives, and its constraints and Jacobian at a
point evaluated before are the same (the finger batches remember their
contacts); at a new point they are a new NLP's to the contacts' tolerance
(each stage continues from its last solution)."""

import numpy as np
import pytest

from design.solvers.optimize.schedule import schedule_of
from design.solvers.optimize.transcription import DesignNLP, NLPSettings
from design.solvers.optimize.trust_region import simulate
from tests.design_cases import LOOP, sharing_simulations, stiffness_space



@pytest.fixture(scope="module")
def baseline():
    space = stiffness_space("lower", "upper")
    d0 = space.scale(space.base_values)
    with sharing_simulations():
        run = simulate(space, d0, LOOP).run
    return space, d0, run


def test_rebound_nlp_solves_as_a_new_one(baseline):
    space, d0, run = baseline
    schedule = schedule_of(run, 0.01)
    settings = NLPSettings(time_step=0.01, max_iter=3)
    wide = (np.clip(d0 - 0.2, 0, 1), np.clip(d0 + 0.2, 0, 1))
    narrow = (np.clip(d0 - 0.05, 0, 1), np.clip(d0 + 0.05, 0, 1))
    nlp = DesignNLP(space, schedule, run, 17.0, settings, box=wide)
    first = nlp.solve()
    again = nlp.rebound(18.5, narrow).solve()
    assert nlp.timings["build_s"] < 0.01                  # nothing built again
    fresh = DesignNLP(space, schedule, run, 18.5, settings, box=narrow).solve()
    assert np.array_equal(again.x, fresh.x) and np.array_equal(again.lam_g, fresh.lam_g)
    assert again.status == fresh.status and again.history == fresh.history
    assert not np.array_equal(first.x, again.x)
    assert np.all(again.d >= narrow[0] - 1e-9) and np.all(again.d <= narrow[1] + 1e-9)


def test_remembered_contacts_give_the_same_constraints(baseline):
    space, d0, run = baseline
    nlp = DesignNLP(space, schedule_of(run, 0.01), run, 18.5, NLPSettings(time_step=0.01))
    x1 = nlp.x0 + 1e-4 * np.random.default_rng(3).uniform(-1, 1, nlp.x0.size)
    g0 = np.asarray(nlp.functions(nlp.x0)[1]).ravel()
    solved = nlp.stage_solves
    g1 = np.asarray(nlp.functions(x1)[1]).ravel()
    assert nlp.stage_solves == 2 * solved                 # a new point: every stage solved
    assert np.array_equal(np.asarray(nlp.functions(nlp.x0)[1]).ravel(), g0)
    assert nlp.stage_solves == 2 * solved                 # x0 again: remembered
    # a stage continues from its last solution: a new NLP, starting from the
    # simulation's guesses, finds the same contacts to the rootfinder's tolerance
    fresh = DesignNLP(space, schedule_of(run, 0.01), run, 18.5, NLPSettings(time_step=0.01))
    np.testing.assert_allclose(np.asarray(fresh.functions(x1)[1]).ravel(), g1, rtol=1e-8,
                               atol=1e-8 * np.abs(g1).max())
