"""A run ended as soon as it shows that it cannot beat a rival design
(design/solvers/grasp/cutoff.py): it ends only where its whole run would
not beat the rival, and up to there it is the whole run."""

import numpy as np

from design.solvers.grasp.cutoff import Cutoff
from design.solvers.grasp.integrate import IntegratorSettings
from design.solvers.grasp.simulation import simulate_grasp
from design.solvers.grasp.validity import finger_limits
from tests.design_cases import shared_simulate_grasp, short_setup


def _ended(setup, cutoff):
    return simulate_grasp(setup, IntegratorSettings(), 6, watch=cutoff.watch(setup))


def _prefix_of(part, whole):
    recs, full = part.trajectory.records, whole.trajectory.records
    return len(recs) < len(full) and all(
        a.t == b.t and np.array_equal(a.y, b.y) for a, b in zip(recs, full))


def test_a_run_ends_once_its_hold_cannot_beat_the_rival_and_not_before():
    """The short grasp's whole run holds H. Against a rival holding H it
    ends early, once its window has closed and less than H of the run is
    left, its records those of the whole run; against a rival holding 1 µs
    less, which it beats, it runs to the end with the whole run's hold."""
    setup = short_setup()
    whole = shared_simulate_grasp(setup)
    hold = whole.summary["hold_time_s"]
    windows = whole.summary["hold_windows"]
    assert hold > 0.3 and whole.summary["stopped"] is None
    ended = _ended(setup, Cutoff(hold, np.inf))
    t = ended.trajectory.records[-1].t
    assert ended.summary["ok"] and "no longer than the" in ended.summary["stopped"]
    assert _prefix_of(ended, whole)
    assert windows[0][1] <= t and setup.duration - t <= hold
    beaten = _ended(setup, Cutoff(hold - 1e-6, np.inf))
    assert beaten.summary["stopped"] is None and beaten.summary["hold_time_s"] == hold


def test_a_run_ends_at_the_first_instant_a_finger_passes_its_limit():
    """Against a cap of half the whole run's peak force (no hold to beat),
    the run ends at the whole run's first record with a finger over its
    limit (the cap or its fold force, the lower), naming it."""
    setup = short_setup()
    whole = shared_simulate_grasp(setup)
    cap = whole.summary["max_finger_force_N"] / 2
    limits = finger_limits(setup, cap)
    first = next(r for r in whole.trajectory.records
                 if any(f.magnitude > lim for f, lim in zip(r.fingers, limits)))
    ended = _ended(setup, Cutoff(-1.0, cap))
    assert _prefix_of(ended, whole) and ended.trajectory.records[-1].t == first.t
    assert ended.summary["stopped"].startswith("finger ")
    assert f"at {first.t:.3f} s" in ended.summary["stopped"]
