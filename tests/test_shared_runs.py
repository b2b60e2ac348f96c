"""The suite's shared simulations (tests/design_cases.py) are shared: a
simulation is keyed by its inputs alone, so a part of a setup the key
cannot compare would make every test that asks for it compute it again."""

from tests.design_cases import LOOP, prefetch_jobs, shared_simulate_grasp, short_setup


def test_every_prefetched_simulation_is_keyed_by_its_inputs_alone():
    jobs = prefetch_jobs()
    assert len(jobs) == 5
    for key, _, users in jobs:
        assert "never shared" not in key, users


def test_the_same_inputs_give_the_same_run_object():
    """Two setups built apart, equal in every input, share one run (the
    short grasp's baseline, which the optimiser tests also ask for)."""
    first = shared_simulate_grasp(short_setup(), LOOP.simulator)
    again = shared_simulate_grasp(short_setup(), LOOP.simulator)
    assert again.trajectory is first.trajectory
