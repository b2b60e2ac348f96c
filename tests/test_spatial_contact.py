"""A spatial rod finger against an ellipsoid (design/solvers/contact/spatial.py):
the planar contact as a special case, rotation invariance, the contact
conditions, friction, and the situations every contact solver must handle."""

import numpy as np
import pytest
from scipy.integrate import quad

from design.physics.beam import Finger
from design.physics.ellipse import Ellipse
from design.physics.kinematics import rot_x
from design.physics.stiffness import UniformEI
from design.solvers.contact import RobustContact
from design.solvers.contact.spatial import FrictionLaw, Quadric, SpatialContact, SpatialState
from tests.problems import thesis_finger, uniform_finger

#: semi-axis (m) along the finger frame's z of the ellipsoid built on a planar ellipse
DEPTH = 0.5


def ellipsoid_on(ell: Ellipse, beta: float = 0.0) -> Quadric:
    """The ellipsoid whose section by the finger's plane is ``ell``, long along z
    (so the contact stays in the plane), turned by β about the finger's axis."""
    R2 = np.array([[np.cos(ell.theta), -np.sin(ell.theta)],
                   [np.sin(ell.theta), np.cos(ell.theta)]])
    Q = np.zeros((3, 3))
    Q[:2, :2] = R2 @ np.diag([1 / ell.a ** 2, 1 / ell.b ** 2]) @ R2.T
    Q[2, 2] = 1 / DEPTH ** 2
    Rx = rot_x(beta)
    return Quadric(Rx @ np.array([*ell.center, 0.0]), Rx @ Q @ Rx.T)


#: objects in the finger frame: light, deep (contact near the middle), tip contact
ELLIPSES = {"light": Ellipse(0.0991, 0.0673, (0.12, -0.07), 0.3),
            "deep": Ellipse(0.0991, 0.0673, (0.14, -0.03), 0.2),
            "tip": Ellipse(0.0991, 0.0673, (0.26, -0.03), 0.5)}


@pytest.mark.parametrize("name", ELLIPSES)
@pytest.mark.parametrize("finger", [thesis_finger(), uniform_finger()], ids=["soft", "EI=0.08"])
def test_the_planar_contact_is_the_in_plane_special_case(finger, name):
    """An object symmetric about the finger's plane: the rod's contact is the
    planar solver's (frictionless), force and point, to 1e-7 relative (two
    transcriptions on the same mesh, K = 10, each within ~1e-9 of exact)."""
    ell = ELLIPSES[name]
    planar = RobustContact(finger, 0.0, intervals=10).solve_frame(ell, "auto", None, None)[0]
    sol, _ = SpatialContact(finger, intervals=10).solve(ellipsoid_on(ell))
    assert sol.converged and sol.contact and planar.contact
    assert sol.tip_contact == planar.tip_contact == (name == "tip")
    scale = np.hypot(*planar.force_on_object_finger_frame)
    np.testing.assert_allclose(sol.force, [*planar.force_on_object_finger_frame, 0.0],
                               atol=1e-7 * scale)
    np.testing.assert_allclose(sol.point, [*planar.point, 0.0], atol=1e-7)


@pytest.mark.parametrize("beta", [0.4, 1.3, -2.0])
def test_a_round_finger_is_indifferent_to_how_the_object_is_turned_about_it(beta):
    """Turning the object by β about the axis of a round finger turns the whole
    solution by β (to 1e-7 relative: Newton and continuation paths differ)."""
    finger = uniform_finger()
    ell = ELLIPSES["deep"]
    flat, _ = SpatialContact(finger).solve(ellipsoid_on(ell))
    turned, _ = SpatialContact(finger).solve(ellipsoid_on(ell, beta))
    Rx = rot_x(beta)
    np.testing.assert_allclose(turned.force, Rx @ flat.force, atol=1e-7 * np.linalg.norm(flat.force))
    np.testing.assert_allclose(turned.point, Rx @ flat.point, atol=1e-8)


def test_a_stiffer_axis_turns_the_push_towards_the_soft_one():
    """An object pressing at 45° between the section axes: a round finger yields
    straight away from it; one 4x stiffer about z yields mostly along y, and
    carries the z part of the normal force without much deflection."""
    ell = ELLIPSES["deep"]
    round_, _ = SpatialContact(uniform_finger()).solve(ellipsoid_on(ell, np.pi / 4))
    stiff_finger = Finger(0.203, UniformEI(0.08), stiff=UniformEI(0.32))
    stiff, _ = SpatialContact(stiff_finger).solve(ellipsoid_on(ell, np.pi / 4))
    assert stiff.converged and round_.converged
    assert abs(round_.point[1] - round_.point[2]) < 1e-8        # along the 45° diagonal
    assert abs(stiff.point[1]) > 1.5 * abs(stiff.point[2])     # yields along y


@pytest.mark.parametrize("name", ["light", "deep", "tip"])
def test_contact_conditions_hold(name):
    """The contact point lies on the surface; inside the span the rod is tangent
    to it; the rod passes nowhere else through the object (1e-9)."""
    quadric = ellipsoid_on(ELLIPSES[name], 0.7)
    sol, state = SpatialContact(thesis_finger()).solve(quadric)
    assert abs(quadric.level(sol.point[:, None])[0]) < 1e-9
    if not sol.tip_contact:
        assert abs(state.post[13:16] @ sol.normal) < 1e-9
    assert sol.penetration == 0.0 and sol.converged


def test_friction_is_coulomb_on_the_tangent_plane():
    """With a given friction vector t the force on the finger is N (n + t_p),
    t_p the tangential part of t: its tangential share is |t_p|."""
    quadric = ellipsoid_on(ELLIPSES["deep"], 0.3)
    t = np.array([0.3, 0.1, -0.2])
    sol, _ = SpatialContact(thesis_finger()).solve(quadric, t)
    on_finger = -sol.force
    normal_part = on_finger @ sol.normal
    tangential = on_finger - normal_part * sol.normal
    t_p = t - (t @ sol.normal) * sol.normal
    assert normal_part > 0
    np.testing.assert_allclose(tangential, normal_part * t_p, atol=1e-9 * normal_part)


@pytest.mark.parametrize("speed", [1e-6, 0.05])
def test_sliding_friction_is_solved_at_the_contact_point(speed):
    """Under the Coulomb law the tangential force is -µ N w / sqrt(|w|² + ε²),
    w the tangential sliding velocity a + B r at the solved contact point r
    itself (1e-9 relative): for ε → 0 its magnitude is µ N, opposite to w."""
    quadric = ellipsoid_on(ELLIPSES["deep"], 0.3)
    a = np.array([0.02, -0.01, 0.03])
    B = np.array([[0.0, -2.1, 0.3], [2.1, 0.0, -0.4], [-0.3, 0.4, 0.0]])   # a rotation's rates
    law = FrictionLaw(mu=0.6, speed=speed, sliding_at_origin=a, sliding_gradient=B)
    sol, _ = SpatialContact(thesis_finger()).solve(quadric, law)
    on_finger = -sol.force
    normal_part = on_finger @ sol.normal
    tangential = on_finger - normal_part * sol.normal
    v = a + B @ sol.point
    w = v - (v @ sol.normal) * sol.normal
    expected = -0.6 * normal_part * w / np.sqrt(w @ w + speed ** 2)
    assert normal_part > 0 and np.linalg.norm(w) > 0.01
    np.testing.assert_allclose(tangential, expected, atol=1e-9 * normal_part)
    np.testing.assert_allclose(sol.extras["friction"] * normal_part, expected,
                               atol=1e-9 * normal_part)


def test_continued_and_fresh_solutions_agree():
    """Following the object in 20 steps gives the solution found directly from
    first touch (one equilibrium on this path; to 1e-8 relative)."""
    solver = SpatialContact(thesis_finger())
    target = ellipsoid_on(ELLIPSES["deep"], 0.5)
    state = None
    for k in np.linspace(0.0, 1.0, 21):
        quadric = target.shifted(np.array([0.0, -0.03, 0.0]) * (1 - k))
        sol, state = solver.solve(quadric, np.zeros(3), state)
    fresh, _ = SpatialContact(thesis_finger()).solve(target)
    np.testing.assert_allclose(sol.force, fresh.force, atol=1e-8 * np.linalg.norm(fresh.force))


def test_a_step_in_pose_and_friction_at_once_lands_where_the_continuation_does():
    """Along a run each solve first tries one Newton step to the new pose and
    the new friction law together; the fallback continues the geometry, then
    the friction. Both reach the same equilibrium (1e-8 relative), under a
    sliding Coulomb law whose rates change from step to step."""
    target = ellipsoid_on(ELLIPSES["deep"], 0.5)
    B = np.array([[0.0, -2.1, 0.3], [2.1, 0.0, -0.4], [-0.3, 0.4, 0.0]])

    def law(k):
        return FrictionLaw(mu=0.6, speed=0.02, sliding_at_origin=np.array([0.02, 0.1 * k, 0.03]),
                           sliding_gradient=(1 + k) * B)

    solver = SpatialContact(thesis_finger())
    _, state = solver.solve(target.shifted(np.array([0.0, -0.003, 0.0])), law(0.0))
    direct, _ = solver.solve(target, law(1.0), state)
    assert isinstance(solver._step(state, target, law(1.0).params), SpatialState)  # taken
    settled, held, _ = solver._settle(target, law(1.0).params, state)
    assert held == 1.0 and direct.normal_force > 1.0
    np.testing.assert_allclose(direct.force, -settled.post[10:13],
                               atol=1e-8 * np.linalg.norm(direct.force))


def test_a_contact_crossing_between_interior_and_tip_is_followed_by_the_chord_method():
    """An object moved 2 mm along the finger across where its contact
    leaves the tip (x0 = 0.2385 -> 0.2405 m), and back: the chord method from
    the solved contact finds the contact in the other mode with that mode's
    latest factors, without a Newton iteration, where Newton from the same
    start (:meth:`SpatialContact._step`) finds the same force (1e-10 of its
    0.34 N: both stop at the residual tolerance)."""
    from design.solvers.contact.spatial import NO_FRICTION
    solver = SpatialContact(thesis_finger())
    at = {x: ellipsoid_on(Ellipse(0.0991, 0.0673, (x, -0.03), 0.0)) for x in (0.2385, 0.2405)}
    for start, end, modes in ((0.2385, 0.2405, ("interior", "tip")),
                              (0.2405, 0.2385, ("tip", "interior"))):
        _, previous = solver.solve(at[start], np.zeros(3))
        solver.solve(at[end], np.zeros(3))               # the other mode's latest factors
        _, previous = solver.solve(at[start], np.zeros(3), previous)
        solver.newton_iterations = 0
        chord = solver._chord(previous, at[end], NO_FRICTION)
        assert (previous.mode, chord.mode) == modes and solver.newton_iterations == 0
        newton = solver._step(previous, at[end], NO_FRICTION)
        assert newton.mode == chord.mode and solver.newton_iterations > 0
        np.testing.assert_allclose(chord.post[10:13], newton.post[10:13],
                                   atol=1e-10 * np.linalg.norm(newton.post[10:13]))


def test_an_accepted_solve_keeps_the_factors_its_chord_solve_converged_with():
    """A short step solved by the chord method and detailed for an accepted
    instant keeps the factors it converged with (the previous state's, here)
    for the next steps, with no Jacobian factored: factoring at every
    accepted instant cost more than the chord iterations it saves."""
    solver = SpatialContact(thesis_finger())
    target = ellipsoid_on(ELLIPSES["deep"], 0.5)
    _, previous = solver.solve(target, np.zeros(3))
    assert previous.lu is not None
    chord = solver.tr[previous.mode].chord
    factored = []
    factor = chord.factor
    chord.factor = lambda z, q: factored.append(z) or factor(z, q)
    try:
        _, state = solver.solve(target.shifted(np.array([0.0, -1e-4, 0.0])), np.zeros(3),
                                previous)
    finally:
        del chord.factor
    assert state.lu is previous.lu and not factored and solver.newton_iterations == 0


def test_no_contact_and_invalid_poses_are_told_apart():
    solver = SpatialContact(thesis_finger())
    far = ellipsoid_on(Ellipse(0.0991, 0.0673, (0.12, -0.2)))
    sol, _ = solver.solve(far)
    assert sol.converged and not sol.contact and "misses" in sol.message
    on_base = ellipsoid_on(Ellipse(0.0991, 0.0673, (0.0, 0.0)))
    sol, _ = solver.solve(on_base)
    assert not sol.converged and "base is inside" in sol.message


def test_a_hairline_touch_presses_as_the_linear_cantilever():
    """A straight finger that enters the object by 1 nm over 20 µm, midway
    between the points of the grid that searches the grazing direction, is
    found inside at its deepest point: a contact, pressing with the force
    of small-deflection theory, δ / ∫₀ᵃ (a - s)² / EI(s) ds for the
    penetration δ at the contact's arc length a (the grasp starts every
    contact 1-2 nm deep, design/solvers/grasp/integrate.py). Within 1e-4:
    the geometric nonlinearity is (F a² / EI)² ~ 1e-14 here, what remains
    is the collocation's integral of EI(s) on six intervals (4e-6
    measured)."""
    finger = thesis_finger()
    r, depth = 0.05, 1e-9
    x_c = finger.length * (100.5 / 200)
    quadric = Quadric(np.array([x_c, 0.0, r - depth]), np.eye(3) / r ** 2)
    sol, state = SpatialContact(finger).solve(quadric)
    assert sol.converged and sol.contact and state is not None
    a = sol.arc_length
    assert abs(a - x_c) < 1e-9
    compliance = quad(lambda s: (a - s) ** 2 / finger.stiffness.ei(s), 0.0, a, limit=200)[0]
    assert sol.normal_force == pytest.approx(depth / compliance, rel=1e-4)
    np.testing.assert_allclose(sol.force, [0.0, 0.0, sol.normal_force],
                               atol=1e-6 * sol.normal_force)
