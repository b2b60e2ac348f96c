"""Finger against an ellipse: the robust solver at every situation the
thesis's solvers could not handle, the invariants, and the thesis's algorithms
measured as baselines."""

import numpy as np
import pytest

from design.physics.beam import Finger
from design.physics.contact import SIDES, FingerPose, Motion, segment_overlap
from design.physics.ellipse import Ellipse
from design.solvers.contact import AlgorithmI, AlgorithmII, RobustContact
from design.reproduce.contact import OMEGA, SPEED, pass_position, scene
from tests.contact_reference import reference
from tests.problems import thesis_finger, uniform_finger

CASE1 = (FingerPose(0.0825, np.radians(126)), Ellipse(0.0991, 0.0673, (-0.1016, 0.184)))
CASE2 = (FingerPose(0.0825, np.radians(72)), Ellipse(0.0991, 0.0673, (0.127, 0.184)))
MOTION = Motion(OMEGA, (SPEED, 0.0))


def contact_geometry(sol, pose, ellipse):
    """Level function at the contact, and the finger tangent's normal component."""
    ell = pose.view(ellipse)
    x, y = sol.point
    g = ell.gradient(x, y)
    n = g / np.hypot(*g)
    t = np.array([np.cos(sol.psi), np.sin(sol.psi)])
    return float(ell.level(x, y)), float(t @ n)


def test_no_contact_is_reported():
    pose, _ = CASE1
    far = Ellipse(0.0991, 0.0673, (-0.5, 0.184))
    sol = RobustContact(thesis_finger(), 0.6).solve(pose, far, "auto", MOTION)
    assert sol.converged and not sol.contact and sol.force == 0.0
    assert "misses" in sol.message


@pytest.mark.parametrize("finger", [thesis_finger(), uniform_finger()], ids=["soft", "EI=0.08"])
@pytest.mark.parametrize("case", [CASE1, CASE2], ids=["case1", "case2"])
@pytest.mark.parametrize("sliding", ["push", "pull"])
def test_contact_point_on_the_ellipse_and_tangent(finger, case, sliding):
    """Eqs. (3.6) and (3.8): the contact lies on the surface and the finger is
    tangent to it there (interior contact); to rounding (dimensionless 1e-9)."""
    pose, ell = case
    sol = RobustContact(finger, 0.6).solve(pose, ell, sliding)
    assert sol.converged and sol.contact and not sol.tip_contact
    level, along = contact_geometry(sol, pose, ell)
    assert abs(level) < 1e-9 and abs(along) < 1e-9
    assert sol.side == sliding and sol.penetration == 0.0


def test_contact_anywhere_along_the_finger():
    """Moving the object along the finger moves the contact from a fifth of its
    length to the tip; every pose converges without a tuned step."""
    finger = uniform_finger()
    solver = RobustContact(finger, 0.6)
    pose = FingerPose(0.0825, 0.0)
    arcs = []
    for x in np.linspace(0.05, 0.30, 26):
        sol = solver.solve(pose, Ellipse(0.05, 0.04, (0.0825 + x, -0.035)), "push")
        assert sol.converged, sol.message
        if sol.contact:
            arcs.append(sol.arc_length / finger.length)
    assert min(arcs) < 0.3 and max(arcs) == pytest.approx(1.0)


def test_tip_contact_slides_on_the_surface():
    """Late in the thesis's pass (φ = 30°) only the tip touches: L = l, the tip
    lies on the surface, and the finger points into the object (no tangency)."""
    finger = uniform_finger()
    pose, ell = scene(30.0, (pass_position(30.0), 0.184))
    sol = RobustContact(finger, 0.6041).solve(pose, ell, "push")
    assert sol.converged and sol.tip_contact
    assert sol.arc_length == pytest.approx(finger.length, rel=1e-12)
    level, along = contact_geometry(sol, pose, ell)
    assert abs(level) < 1e-9 and along < -1e-3


@pytest.mark.parametrize("depth", [1e-9, 1e-7, 1e-5, 1e-4])
def test_grazing_contact_force_vanishes_with_the_overlap(depth):
    """An object that overlaps the straight finger by δ gives F ∝ δ as δ -> 0."""
    finger = uniform_finger()
    pose = FingerPose(0.0825, 0.0)
    b = 0.04
    ell = Ellipse(0.06, b, (0.0825 + 0.12, -b + depth))   # top of the ellipse just above y_f = 0
    sol = RobustContact(finger, 0.6).solve(pose, ell, "push")
    assert sol.converged and sol.contact and sol.force > 0
    stiffness = sol.force / depth                        # N/m, the finger's transverse stiffness
    assert 1 < stiffness < 1e3
    ref = RobustContact(finger, 0.6).solve(pose, Ellipse(0.06, b, (0.2025, -b + 1e-9)), "push")
    assert stiffness == pytest.approx(ref.force / 1e-9, rel=max(3 * depth / 1e-3, 1e-4))


def test_slope_near_90_degrees():
    """Case-2-like pull where the contact slope crosses 90° (Algorithm I's
    failure: it oscillates near vertical tangents)."""
    solver = RobustContact(thesis_finger(), 0.6)
    pose = CASE2[0]
    slopes = []
    for x0 in [0.145, 0.15, 0.155, 0.16]:
        sol = solver.solve(pose, Ellipse(0.0991, 0.0673, (x0, 0.184)), "pull")
        assert sol.converged and sol.contact
        level, along = contact_geometry(sol, pose, Ellipse(0.0991, 0.0673, (x0, 0.184)))
        assert abs(level) < 1e-9 and abs(along) < 1e-9
        slopes.append(np.degrees(sol.psi))
    assert min(slopes) < -90 < max(slopes)


@pytest.mark.parametrize("mu", [0.0, 1.2, 2.0])
def test_friction_sets_the_force_direction(mu):
    """The force on the finger leans from the contact normal by atan µ
    (α + ψ0 = π/2 + atan µ, eq. 3.7), towards the tip for the thesis's convention."""
    pose, ell = CASE1
    sol = RobustContact(thesis_finger(), mu).solve(pose, ell, "push")
    assert sol.converged
    assert sol.alpha + sol.psi == pytest.approx(np.pi / 2 + np.arctan(mu), abs=1e-9)
    assert sol.friction == ("none" if mu == 0 else "tipward")


@pytest.mark.parametrize("ei", [1e-4, 1e-3, 10.0, 100.0])
def test_very_soft_and_very_stiff_fingers(ei):
    """The object is rigid and placed, so the contact geometry does not depend on
    how stiff the finger is and the force is proportional to EI: over six decades
    of EI the solver converges to the same shape (the unknowns are scaled by EI)."""
    pose, ell = CASE1
    sol = RobustContact(uniform_finger(ei), 0.6).solve(pose, ell, "push")
    ref = RobustContact(uniform_finger(0.08), 0.6).solve(pose, ell, "push")
    assert sol.converged and sol.contact and sol.penetration == 0.0
    assert sol.force == pytest.approx(ref.force * ei / 0.08, rel=1e-8)
    np.testing.assert_allclose(sol.point, ref.point, atol=1e-11)


def test_finger_never_passes_through_the_object():
    """Random poses, sizes and orientations around the finger: every converged
    contact has no point of the finger inside the object."""
    rng = np.random.default_rng(3)
    solver = RobustContact(thesis_finger(), 0.6)
    checked = 0
    for _ in range(40):
        phi = rng.uniform(0, 2 * np.pi)
        pose = FingerPose(0.0825, phi)
        d, off = rng.uniform(0.12, 0.3), rng.uniform(-0.08, 0.08)
        c = pose.base + d * np.array([np.cos(phi), np.sin(phi)]) + off * np.array([-np.sin(phi), np.cos(phi)])
        ell = Ellipse(rng.uniform(0.03, 0.1), rng.uniform(0.03, 0.08), tuple(c), rng.uniform(0, np.pi))
        if ell.level(*pose.base) <= 0:
            continue
        sol = solver.solve(pose, ell, rng.choice(["push", "pull"]))
        if sol.contact and sol.converged:
            checked += 1
            inside = pose.view(ell).distance_outside(sol.shape_x, sol.shape_y)
            assert inside.min() > -1e-9
    assert checked >= 15


def test_pass_continues_the_solution_and_releases():
    """Along the thesis's pass each pose continues the previous one: the forces
    equal those of solving each pose alone (push: no history dependence), the
    contact starts and ends with F -> 0."""
    finger = uniform_finger()
    phis = np.arange(180.0, -0.1, -3.0)
    poses, ells = zip(*(scene(p, (pass_position(p), 0.184)) for p in phis))
    solver = RobustContact(finger, 0.6041)
    sols = solver.solve_pass(list(poses), list(ells), "push")
    assert all(s.converged for s in sols)
    forces = np.array([s.force for s in sols])
    touching = np.flatnonzero(forces > 0)
    assert forces[touching[0]] < 1.0 and forces[touching[-1]] < 2.5
    for i in touching[::4]:
        alone = RobustContact(finger, 0.6041).solve(poses[i], ells[i], "push")
        assert alone.force == pytest.approx(sols[i].force, rel=1e-8)


def test_stiffness_scaling_scales_force_not_geometry():
    """EI -> k EI: every force k times, contact point and shape unchanged."""
    pose, ell = CASE1
    base = RobustContact(thesis_finger(), 0.6).solve(pose, ell, "push")
    for k in [0.1, 7.0]:
        finger = Finger(0.203, thesis_finger().stiffness.scaled(k))
        sol = RobustContact(finger, 0.6).solve(pose, ell, "push")
        assert sol.force == pytest.approx(k * base.force, rel=1e-8)
        np.testing.assert_allclose(sol.point, base.point, atol=1e-11)
        assert sol.psi == pytest.approx(base.psi, abs=1e-9)


def test_mirror_about_world_x_exchanges_push_and_pull():
    """Mirror the scene about the world X axis (φ -> -φ, Y -> -Y, drum turning the
    other way): the solution mirrors, push and pull exchange, friction keeps
    its sense along the finger."""
    pose, ell = CASE1
    solver = RobustContact(thesis_finger(), 0.6)
    sol = solver.solve(pose, ell, "auto", MOTION)
    mpose = FingerPose(pose.radius, -pose.angle)
    mell = Ellipse(ell.a, ell.b, (ell.center[0], -ell.center[1]), -ell.theta)
    mmotion = Motion(-MOTION.drum_speed, (MOTION.object_velocity[0], -MOTION.object_velocity[1]))
    mir = solver.solve(mpose, mell, "auto", mmotion)
    assert mir.side == {"push": "pull", "pull": "push"}[sol.side]
    assert mir.friction == sol.friction
    assert mir.force == pytest.approx(sol.force, rel=1e-9)
    np.testing.assert_allclose(mir.force_vector, sol.force_vector * [1, -1], atol=1e-9)
    np.testing.assert_allclose(mir.point_world, sol.point_world * [1, -1], atol=1e-11)


@pytest.mark.parametrize("case", [CASE1, CASE2], ids=["case1", "case2"])
def test_base_moment_balances_the_contact_force(case):
    pose, ell = case
    sol = RobustContact(thesis_finger(), 0.6).solve(pose, ell, "auto", MOTION)
    fx, fy = -sol.force * np.cos(sol.alpha), sol.force * np.sin(sol.alpha)   # on the finger
    x, y = sol.point
    # collocation tip error ~1e-9 m times F ~ 10 N
    assert sol.extras["base_moment"] == pytest.approx(x * fy - y * fx, abs=1e-7)


def test_automatic_friction_opposes_the_sliding_velocity():
    """The sliding velocity by the implicit-function theorem agrees with a finite
    difference of two poses 0.1 ms apart (the finger's material point at the
    contact, followed), and the friction on the finger opposes it."""
    finger = uniform_finger()
    pose, ell = scene(108.0, (pass_position(108.0), 0.184))
    solver = RobustContact(finger, 0.6041)
    sol = solver.solve(pose, ell, "auto", MOTION)
    dt = 1e-4
    pose2 = FingerPose(pose.radius, pose.angle - OMEGA * dt)
    ell2 = Ellipse(ell.a, ell.b, (ell.center[0] + SPEED * dt, ell.center[1]))
    later = solver.solve(pose2, ell2, "auto", MOTION)
    s_star = sol.arc_length                   # the material point at the contact, followed
    p2 = pose2.to_world(np.interp(s_star, later.shape_s, later.shape_x),
                        np.interp(s_star, later.shape_s, later.shape_y))[:, 0]
    t_c = pose.vector_to_world([np.cos(sol.psi), np.sin(sol.psi)])
    v_fd = float(((p2 - sol.point_world) / dt - np.array([SPEED, 0.0])) @ t_c)
    v_ift = sol.extras["sliding_velocity"]
    # first-order difference over 0.1 ms: O(dt) ~ 1e-3 relative
    assert v_ift == pytest.approx(v_fd, rel=1e-2)
    # the contact slides towards the finger's tip (v > 0): friction on it is baseward
    assert v_ift > 0.05 and sol.friction == "baseward"


def test_automatic_side_follows_the_history():
    """With the motion played back from first touch, Case 1 and Case 2 are both
    pushes: at φ = 72° the finger has been pushing the object since φ ≈ 155°
    (Table 3-5's φ = 72° row is that push, 8.055 N). The thesis's Case 2
    (Figure 3-7) is the other equilibrium at that pose, the finger pulled to
    -y_f, which the object reaches only from the other side: forcing pull
    gives it, the independent least-energy reference's equilibrium on that
    side (tests/contact_reference.py, to its 1e-7; 18.24 N, which the
    thesis's 18.72 N exceeds by 2.6 %, more than the report's 2 %: see
    test_reproduction_contact.py)."""
    finger = uniform_finger()
    s1 = RobustContact(finger, 0.6).solve(*CASE1, "auto", MOTION)
    s2 = RobustContact(finger, 0.6).solve(*CASE2, "auto", MOTION)
    assert (s1.side, s2.side) == ("push", "push")
    pulled = RobustContact(finger, 0.6).solve(*CASE2, "pull")
    ref = reference(finger, CASE2[0].view(CASE2[1]), 0.6, SIDES["pull"])
    assert pulled.side == "pull" and ref.side == SIDES["pull"]
    assert np.hypot(*np.subtract(pulled.point, ref.point)) < 1e-7
    assert pulled.force == pytest.approx(ref.force, rel=1e-7)


def test_algorithm_one_needs_a_tuned_step():
    """Table 3-2 / Figures 3-6, 3-7: Case 1 converges for β = 0.05 and 0.6
    (thesis: 58 and 9 iterations; ours 51 and 4 with its update written as
    printed); Case 2 converges for β = 0.05 and fails for β = 0.6, as the
    thesis found (β ≤ 0.05 there)."""
    soft = thesis_finger()
    c1 = {b: AlgorithmI(soft, 0.6, step=b).solve(*CASE1, "push") for b in [0.05, 0.6]}
    assert all(s.converged for s in c1.values())
    assert c1[0.05].iterations > 5 * c1[0.6].iterations
    assert AlgorithmI(soft, 0.6, step=0.05).solve(*CASE2, "pull").converged
    assert not AlgorithmI(soft, 0.6, step=0.6).solve(*CASE2, "pull").converged


def test_algorithm_two_has_no_tip_contact():
    """Algorithm II agrees with the robust solver where the contact is inside the
    span (FDM error O(h^2)), but at a tip contact its only root puts the contact
    beyond the finger's end: a spurious solution."""
    soft = thesis_finger()
    robust = RobustContact(soft, 0.6).solve(*CASE1, "push")
    alg2 = AlgorithmII(soft, 0.6, nodes=155).solve(*CASE1, "push")
    assert alg2.converged and alg2.force == pytest.approx(robust.force, rel=1e-3)
    pose, ell = scene(30.0, (pass_position(30.0), 0.184))
    tip = AlgorithmII(soft, 0.6041, nodes=155).solve(pose, ell, "push")
    assert not tip.converged and "spurious" in tip.message
    assert RobustContact(soft, 0.6041).solve(pose, ell, "push").tip_contact


def test_invalid_pose_is_reported():
    pose = FingerPose(0.0825, 0.0)
    inside = Ellipse(0.1, 0.1, (0.0825, 0.0))
    sol = RobustContact(uniform_finger(), 0.6).solve(pose, inside, "push")
    assert not sol.converged and "base is inside" in sol.message
    assert segment_overlap(pose.view(inside), 0.203) < 0


def sticking_scene(mu=0.6, **options):
    """Case 1 in the finger frame, the object moving along -y_f at 5 cm/s
    and its surface at the contact moving with the finger's material point
    of the frictionless equilibrium: the sliding speed vanishes at friction
    ratio 0, so the contact sticks there. Returns (solver, ellipse, kinematics)."""
    pose, ell_w = CASE1
    ell, finger = pose.view(ell_w), uniform_finger()
    solver = RobustContact(finger, mu, **options)
    _, free = RobustContact(finger, 0.0).solve_frame(ell, "push", None, None)
    rates = np.array([0.0, -0.05, 0.0, 0.0, 0.0])
    speed = solver._sliding_velocity(free, lambda p: (rates, np.zeros(2)))
    t_c = free.post[9:11]                        # the sliding tangent
    return solver, ell, lambda p: (rates, speed * t_c)


def fail_continuation(monkeypatch, solver, when, name="_continue"):
    """Make the solver's continuation (or search from first touch, ``name``)
    to a friction ratio τµ fail where ``when(τµ)``."""
    real = getattr(solver, name)
    monkeypatch.setattr(solver, name, lambda state, target, tau_mu: (
        (None, f"{name} forced to fail") if when(tau_mu) else real(state, target, tau_mu)))


def test_sticking_contact_is_found_where_the_sliding_stops():
    """Bisection on the friction ratio stops where the sliding speed is below
    STICK_SPEED = 1e-7 m/s; the speed changes by ~5 mm/s across the ratio's
    range 2µ, so the ratio is within ~3e-5 of 0."""
    solver, ell, kin = sticking_scene()
    sol, _ = solver.solve_frame(ell, "auto", kin, None)
    assert sol.converged and sol.friction == "stick", sol.message
    assert abs(sol.extras["sliding_velocity"]) <= 1e-7
    assert sol.extras["friction_ratio"] == pytest.approx(0.0, abs=1e-4)


@pytest.mark.parametrize("detail", [True, False])
def test_stick_bisection_stopped_early_is_not_converged(monkeypatch, detail):
    """No equilibrium at the bisection's midpoints: the stick is not resolved,
    and the solution (with its shape, or the brief one of trial evaluations)
    says so instead of reporting a stick."""
    solver, ell, kin = sticking_scene()
    fail_continuation(monkeypatch, solver, lambda tau_mu: abs(tau_mu) < 0.6 * (1 - 1e-9))
    sol, _ = solver.solve_frame(ell, "auto", kin, None, detail=detail)
    assert not sol.converged and "sticking contact not resolved" in sol.message
    assert "_continue forced to fail" in sol.message


def test_failed_friction_reversal_is_not_converged(monkeypatch):
    """With friction kept at the edge of sliding (the grasp's setting), a
    finger sliding against its friction faster than the reversal speed has
    the friction reversed; if no equilibrium with the reversed friction is
    found, the solution is not converged (not the old friction reported as
    a success)."""
    solver, ell, kin = sticking_scene(reversal_speed=1e-5)
    sol, _ = solver.solve_frame(ell, "auto", kin, None)
    assert sol.converged and sol.friction == "baseward", sol.message
    for name in ("_continue", "_from_first_touch"):
        fail_continuation(monkeypatch, solver, lambda tau_mu: tau_mu < 0, name)
    sol, _ = solver.solve_frame(ell, "auto", kin, None)
    assert not sol.converged and "the friction could not reverse" in sol.message
    assert sol.friction == "tipward"


def _conic(ell: Ellipse):
    return np.asarray(ell.center, float), ell.matrix


@pytest.mark.parametrize("shift", [2e-4, 2e-3])
def test_a_trial_in_one_newton_solve_is_the_stepped_continuation(shift):
    """An integrator's trial evaluation (RobustContact.continue_trial: one
    Newton solve on the section as a conic, in one compiled call) gives the
    contact the stepped continuation gives from the same state (solve_frame,
    friction kept): force and angle to 1e-9 relative (both solve to a 1e-12
    residual; the conic and the axes forms of the ellipse round differently).
    The grasp scenes' 6-interval mesh, whose compiled functions the suite
    builds anyway on an empty cache."""
    pose, ell_w = CASE1
    ell, solver = pose.view(ell_w), RobustContact(thesis_finger(), 0.4, intervals=6)
    _, state = solver.solve_frame(ell, "push", None, None)
    moved = ell.shifted(0.0, shift)
    trial = solver.continue_trial(state, *_conic(moved))
    assert trial is not None
    stepped, _ = solver.solve_frame(moved, "auto", None, state, settle=False, detail=False)
    assert stepped.converged and trial[0].converged
    assert trial[0].force == pytest.approx(stepped.force, rel=1e-9)
    assert trial[0].alpha == pytest.approx(stepped.alpha, rel=1e-9)
    assert trial[0].force > state.post[3]            # pressed further in: more force
    # the state it returns continues like any other: a commit from it
    again, _ = solver.solve_frame(moved, "auto", None, trial[1])
    assert again.force == pytest.approx(stepped.force, rel=1e-9)


def test_a_trial_that_needs_more_than_one_newton_solve_is_left_to_the_steps():
    """Where one Newton solve is not the whole answer, continue_trial returns
    None and the caller takes the stepped path: the object moved clear of the
    straight finger (a release), or so far that Newton from the old state does
    not converge within MAX_STEP_ITERATIONS. A long move that Newton does
    converge (undamped: no line search) must land on the stepped path's
    solution."""
    pose, ell_w = CASE1
    ell, solver = pose.view(ell_w), RobustContact(thesis_finger(), 0.4, intervals=6)
    _, state = solver.solve_frame(ell, "push", None, None)
    clear = ell.shifted(0.0, -0.15)
    assert segment_overlap(clear, solver.finger.length) >= 0.0
    assert solver.continue_trial(state, *_conic(clear)) is None
    far = ell.shifted(-0.04, 0.01)                      # 6.3 N -> 212 N
    assert solver.continue_trial(state, *_conic(far)) is None
    sol, _ = solver.solve_frame(far, "auto", None, state, settle=False, detail=False)
    assert sol.converged and sol.force > 30 * state.post[3]   # the steps get there
    long = ell.shifted(-0.03, 0.01)                     # 6.3 N -> 74 N in one solve
    trial = solver.continue_trial(state, *_conic(long))
    stepped, _ = solver.solve_frame(long, "auto", None, state, settle=False, detail=False)
    assert trial is not None and trial[0].force == pytest.approx(stepped.force, rel=1e-9)
