"""The spatial finger model inside a grasp run (docs/MODEL.md, "spatial")."""

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from design.io.scene import load_scene
from design.reproduce.grasp import MEAN_START, mean_bird_setup
from design.run.grasp import setup_of
from design.solvers.newton import Chord
from design.solvers.contact.belt_continuation import BIRD_MODES, Belted
from design.solvers.contact.spatial import SpatialState, segment_level
from design.solvers.grasp.fingers import RATE_STEP, FingerForces, _nearer, body_quadric


def fingers_of(setup) -> FingerForces:
    return FingerForces(setup.grasper, setup.bird, setup.drum_speed, setup.finger_friction,
                        model="spatial", intervals=6)


def test_the_loads_are_a_function_of_the_state():
    """Loads at an accepted instant, continued from the state committed one
    step earlier, equal the loads there continued from the state committed
    at that instant itself (1e-9 relative: the Newton tolerance). Table 5-3's
    mean bird, soft lower fingers, at Table 5-3's X0 = -0.075 m with the
    fingers at Table 5-1's angles: finger 4a slides along it (µ = 0.4). The friction is solved at the contact point itself; taken from
    the previous solution's point, it made the loads jump at every accepted
    step (0.03 m/s² in 0.05 m/s², measured on the football), which forced
    1e-4 s steps."""
    setup = mean_bird_setup("soft")
    b = setup.bird
    y0 = np.array([MEAN_START, b.gamma + 0.002, 0.0, setup.conveyor.speed, 0.0, 0.0])
    y1 = y0 + 0.004 * np.concatenate([y0[3:], [0.0, 0.0, 0.0]])
    stepping = fingers_of(setup)
    stepping.evaluate(0.0, y0, commit=True)
    committed, states = stepping.evaluate(0.004, y1, commit=True)
    again = fingers_of(setup)
    again.states = list(stepping.states)
    trial, _ = again.evaluate(0.004, y1)
    force = next(s for s in states if s.magnitude > 0)
    assert force.magnitude > 5.0 and abs(force.solution.extras["friction"] @ force.solution.normal) < 1e-9
    loads = np.array([committed.qx, committed.qz, committed.ty])
    np.testing.assert_allclose([trial.qx, trial.qz, trial.ty], loads,
                               atol=1e-9 * np.abs(loads).max())


def test_a_varied_state_finds_the_contacts_the_accepted_state_finds(monkeypatch):
    """A difference quotient's varied state (each coordinate stepped by
    1e-6), its contacts continued from the trial at the unvaried state
    instead of from the accepted one: the same loads (1e-9 relative: the
    Newton tolerance) in fewer chord updates, and the object
    as it was. The main job's scene 4 ms after an accepted instant, fingers
    on the bird and finger 5a on the belt."""
    (forces,), (y1, _) = main_job_fingers(1)
    t = 0.004
    trial, _ = forces.evaluate(t, y1)
    states = list(forces.states)
    assert trial.qz != 0.0
    runs = [0]                                 # chord updates (design.solvers.newton.Chord)
    solve = Chord.solve

    def counted(self, *args):
        before = self.updates
        root = solve(self, *args)
        runs[0] += self.updates - before
        return root

    monkeypatch.setattr(Chord, "solve", counted)
    for j in range(6):
        varied = y1.copy()
        varied[j] += 1e-6
        before = runs[0]
        near = forces.varied(t, varied, (t, y1))
        cost = runs[0] - before
        other = main_job_fingers(1)[0][0]
        before = runs[0]
        fresh, _ = other.evaluate(t, varied)
        assert cost < runs[0] - before
        loads = np.array([fresh.qx, fresh.qz, fresh.ty])
        np.testing.assert_allclose([near.qx, near.qz, near.ty], loads,
                                   atol=1e-9 * np.abs(loads).max())
        assert forces.states == states


def test_a_trial_in_another_mode_is_no_start_without_its_own_factors():
    """A trial that switched the contact into another mode (tip, fewer
    unknowns) and kept no Jacobian factors cannot take the accepted state's
    (of the interior mode's size): the accepted state is the start; a trial
    in the accepted state's mode takes its factors."""
    (forces,), (y1, _) = main_job_fingers(1)
    accepted = next(s for s in forces.states if isinstance(s, SpatialState) and s.lu is not None)
    other = "tip" if accepted.mode == "interior" else "interior"
    switched = replace(accepted, mode=other, z=accepted.z[:-1], lu=None)
    assert _nearer(accepted, switched) is accepted
    same = _nearer(accepted, replace(accepted, lu=None))
    assert same.lu is accepted.lu and same is not accepted


def main_job_fingers(copies: int) -> tuple[list[FingerForces], tuple[np.ndarray, np.ndarray]]:
    """The main job's scene with the bird at X0 = -0.075 m on the belt:
    ``copies`` spatial FingerForces committed at t = 0, and the bird's
    states 4 and 8 ms on (riding the belt)."""
    setup = setup_of(load_scene(Path(__file__).parents[1] / "problems" / "hold_time.yaml").scene)
    b = setup.bird
    y0 = np.array([MEAN_START, b.gamma + 0.002, 0.0, setup.conveyor.speed, 0.0, 0.0])
    forces = [FingerForces(setup.grasper, b, setup.drum_speed, setup.finger_friction,
                           model="spatial", intervals=6, belt=setup.belt,
                           belt_friction=setup.finger_belt_friction) for _ in range(copies)]
    for f in forces:
        f.evaluate(0.0, y0, commit=True)
    return forces, tuple(y0 + dt * np.concatenate([y0[3:], [0.0, 0.0, 0.0]])
                         for dt in (0.004, 0.008))


def test_a_commit_keeps_the_trial_solved_at_its_instant():
    """An accepted instant's commit reuses the trial evaluated there (an
    adaptive step's last stage), solving again only the fingers the trial
    left out, waiting for a first touch of the bird: its loads, forces,
    finger shapes, out-of-plane shares and the states later evaluations
    continue from are those of a commit that solves afresh, to the last bit
    (the same computation from the same committed start), and so are the
    next trial's loads. The main job's scene with the bird at X0 = -0.075 m:
    finger 4a presses it (a bird-only contact), the three fingers 5 rest on
    the belt."""
    (reused, fresh), (y1, y2) = main_job_fingers(2)
    reused.evaluate(0.004, y1)
    solves = reused.solves
    kept, kept_states = reused.evaluate(0.004, y1, commit=True)
    waiting = [s for s in kept_states if isinstance(s.continued, Belted)
               and s.continued.mode not in BIRD_MODES]
    assert len(waiting) == 3 and reused.solves == solves + len(waiting)
    solved, solved_states = fresh.evaluate(0.004, y1, commit=True)
    kinds = {type(s.continued).__name__ for s in solved_states if s.solution is not None}
    assert kinds == {"SpatialState", "Belted"} and max(s.magnitude for s in solved_states) > 5.0
    assert (kept.qx, kept.qz, kept.ty) == (solved.qx, solved.qz, solved.ty)
    for k, s in zip(kept_states, solved_states):
        assert np.array_equal(k.force, s.force)
        assert (k.normal_out_of_plane, k.sweep_out_of_plane) == \
            (s.normal_out_of_plane, s.sweep_out_of_plane)
        if s.solution is not None:
            assert np.array_equal(k.solution.shape_points, s.solution.shape_points)
            assert all(np.array_equal(getattr(k.continued.lu, a), getattr(s.continued.lu, a))
                       for a in ("lu", "piv"))
    nxt = [f.evaluate(0.008, y2)[0] for f in (reused, fresh)]
    assert (nxt[0].qx, nxt[0].qz, nxt[0].ty) == (nxt[1].qx, nxt[1].qz, nxt[1].ty)


def test_a_commit_solves_again_where_its_trial_lost_the_continued_equilibrium():
    """A trial finds a fold at a coarser stall than a commit
    (design/solvers/contact/belt_continuation.py): where one of its fingers
    lost the continued equilibrium, the commit at its instant solves every
    finger again instead of keeping the trial."""
    ([fingers], (y1, _)) = main_job_fingers(1)
    _, states = fingers.evaluate(0.004, y1)
    pressing = next(s for s in states if s.solution is not None)      # finger 4a
    pressing.solution.extras["continuation_lost"] = True
    solves = fingers.solves
    _, committed = fingers.evaluate(0.004, y1, commit=True)
    assert fingers.solves == solves + sum(s.solution is not None for s in committed) == solves + 4


def test_the_surface_motion_is_the_birds_seen_from_the_turning_finger():
    """A spatial finger's friction law takes the bird's surface velocity in
    the finger frame as an affine field v0 + G p: at any point it is the
    difference quotient over RATE_STEP of the point carried with the bird
    and seen from the drum-turned frame (1e-8 m/s: rounding of positions of
    0.1 m divided by the 1e-6 s step). The mean bird moving and pitching
    at finger 4a. Its quadric and the straight finger's level, computed
    with every finger's at once, are the single finger's (to rounding), and
    its parameters' rates the forward difference of that quadric."""
    setup = mean_bird_setup("soft")
    forces = fingers_of(setup)
    b = setup.bird
    y = np.array([MEAN_START, b.gamma + 0.002, 0.05, setup.conveyor.speed, -0.03, 0.8])
    t, dt = 0.3, RATE_STEP
    body = forces.ellipsoid(y)
    i = [gf.name for gf in setup.grasper.fingers].index("4a")
    base, R = forces.frame(i, t)
    view = forces._views(t, y, body)[i]
    quadric = body_quadric(body, base, R)
    np.testing.assert_allclose(view.quadric.params, quadric.params, rtol=1e-13, atol=1e-15)
    length = setup.grasper.fingers[i].finger.length
    assert view.level == pytest.approx(segment_level(quadric, length), rel=1e-12, abs=1e-14)
    motion = view.motion
    y2 = y.copy()
    y2[:3] += dt * y[3:]
    later = forces.ellipsoid(y2)
    base2, R2 = forces.frame(i, t + dt)
    for p in np.random.default_rng(0).uniform(-0.1, 0.1, (5, 3)):
        p_w = base + R @ p
        carried = np.asarray(later.center) + later.rotation @ (
            body.rotation.T @ (p_w - np.asarray(body.center)))
        expected = (R2.T @ (carried - base2) - p) / dt
        np.testing.assert_allclose(motion(p)[1], expected, rtol=0, atol=1e-8)
    assert np.linalg.norm(motion.gradient) > 0.5          # the pitch rate and drum turn show
    # the quadric's parameter rates: the same forward difference of the
    # quadric seen from the finger's frame dt on
    rates = (body_quadric(later, base2, R2).params - quadric.params) / dt
    np.testing.assert_allclose(motion.rates, rates, rtol=1e-9, atol=1e-6)
    assert np.abs(rates).max() > 0.1
