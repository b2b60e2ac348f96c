"""A finger pressed on the moving belt, alone and with the bird (design/solvers/
contact/belt_continuation.py and its two finger models).

References independent of the toolkit's collocation: the elastica with a
unilateral tip constraint on a moving plane, solved by
``scipy.integrate.solve_bvp``; the small-deflection closed form; for two
loads, the elastica under the solved forces integrated by ``solve_bvp``.

The setting (finger frame, clamped at the origin along +x): the belt's
upward normal n = (-sin β, cos β) makes the finger point down into it at β;
its straight tip would lie δ below the surface. The belt slides along its
line at 0.3 m/s relative to the finger, so that its regularised Coulomb
friction (ε = 0.02 m/s) is µN within 0.3 %.
"""

from __future__ import annotations

from dataclasses import replace
from functools import lru_cache
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_bvp

from design.physics.beam import Finger
from design.physics.kinematics import rot_x
from design.physics.stiffness import UniformEI
from design.reproduce.grasp import football_setup
from design.solvers.contact import RobustContact
from design.solvers.contact.belt_continuation import (EVENT_DEPTH, GRAZE_DEPTH, BeltedContact,
                                                      Belted,
                                                      Plane, deepest)
from design.solvers.contact.planar_belt import PlanarBeltContact
from design.solvers.contact.spatial import FrictionLaw, Quadric, SpatialContact
from design.solvers.contact.spatial_belt import SpatialBeltContact, _nodes
from tests.problems import thesis_finger

LENGTH = 0.152
BETA = np.radians(15.0)
NORMAL = np.array([-np.sin(BETA), np.cos(BETA)])
LINE = np.array([np.cos(BETA), np.sin(BETA)])      # the belt's direction, tipwards
MU, EPS, SLIDE = 0.4, 0.02, 0.3


def belt_offset(depth: float) -> float:
    """e of the belt n·p = e with the straight tip ``depth`` below it."""
    return float(NORMAL @ np.array([LENGTH, 0.0])) + depth


@lru_cache(maxsize=None)
def solvers(kind: str):
    """(planar, spatial) belt solvers of a finger: ``thesis`` (soft, non-uniform) or ``uniform``."""
    finger = Finger(LENGTH, thesis_finger().stiffness) if kind == "thesis" else \
        Finger(LENGTH, UniformEI(0.08))
    planar = PlanarBeltContact(RobustContact(finger, MU, intervals=8))
    spatial = SpatialBeltContact(SpatialContact(finger, intervals=8))
    return finger, planar, spatial


def planar_law(mu: float) -> np.ndarray:
    """The finger slides tipwards over the belt at SLIDE (uniform in p)."""
    return np.array([mu, EPS, *(SLIDE * LINE), 0.0, 0.0, 0.0, 0.0])


def spatial_law(mu: float, turn: np.ndarray = np.eye(3)) -> FrictionLaw:
    return FrictionLaw(mu=mu, speed=EPS, sliding_at_origin=turn @ np.array([*SLIDE * LINE, 0.0]))


def solve_planar(kind: str, depth: float, mu: float):
    _, planar, _ = solvers(kind)
    sol, state = planar.solve(None, 0.0, Plane(NORMAL, belt_offset(depth)), planar_law(mu))
    assert sol.converged and state.mode == "belt", sol.message
    return sol.belt_normal_force, sol.belt_point


def solve_spatial(kind: str, depth: float, mu: float, turn: np.ndarray = np.eye(3)):
    _, _, spatial = solvers(kind)
    plane = Plane(turn @ np.array([*NORMAL, 0.0]), belt_offset(depth))
    sol, state = spatial.solve(None, FrictionLaw(), plane, spatial_law(mu, turn))
    assert sol.converged and state.mode == "belt", sol.message
    return sol.belt_normal_force, sol.belt_point


def reference(finger: Finger, depth: float, mu: float) -> tuple[float, np.ndarray]:
    """The elastica with its tip on the belt: unknowns x, y, ψ, M over s and the
    normal force N; the tip force N (n - µ w/sqrt(w² + ε²) t) with the
    sliding w = SLIDE along t. solve_bvp at tol 1e-10."""
    e = belt_offset(depth)
    direction = NORMAL - mu * SLIDE / np.hypot(SLIDE, EPS) * LINE
    ei = finger.stiffness.ei

    def rhs(s, y, p):
        fx, fy = p[0] * direction
        return np.vstack([np.cos(y[2]), np.sin(y[2]), y[3] / ei(s),
                          fx * np.sin(y[2]) - fy * np.cos(y[2])])

    def bc(ya, yb, p):
        return np.array([ya[0], ya[1], ya[2], yb[3], NORMAL @ yb[:2] - e])

    s = np.linspace(0.0, LENGTH, 41)
    guess = np.vstack([s, np.zeros_like(s), np.zeros_like(s), np.zeros_like(s)])
    sol = solve_bvp(rhs, bc, s, guess, p=[0.0], tol=1e-10, max_nodes=100000)
    assert sol.status == 0, sol.message
    return float(sol.p[0]), sol.y[:2, -1]


@pytest.mark.parametrize("depth", [2e-3, 7.3e-3, 3e-2])
@pytest.mark.parametrize("mu", [0.0, MU])
def test_both_finger_models_press_on_the_belt_as_the_elastica_does(depth, mu):
    """The thesis's finger (soft, non-uniform) 2, 7.3 (finger 5 of Table 5-1)
    and 30 mm below the belt, with and without friction: the normal force
    within 1e-6 relative and the tip within 1e-7 m of solve_bvp's (both
    solutions resolve the elastica to ~1e-9); the spatial rod, loaded in its
    plane, gives the planar finger's answer."""
    finger, _, _ = solvers("thesis")
    force, tip = reference(finger, depth, mu)
    for model in (solve_planar, solve_spatial):
        f, p = model("thesis", depth, mu)
        assert f == pytest.approx(force, rel=1e-6)
        np.testing.assert_allclose(p[:2], tip, atol=1e-7)


@pytest.mark.parametrize("mu, sense", [(0.0, 0), (MU, 1)])
def test_a_shallow_press_follows_the_small_deflection_closed_form(mu, sense):
    """δ = 0.1 mm on a uniform finger: the tip deflects δ / cos β across the
    finger, so the transverse force 3 EI δ / (l³ cos β) balances N (cos β -
    µ sin β) (friction on the finger against its tipward sliding). Within
    1e-3: the beam-column and large-deflection corrections are O(δ / l) and
    O(F l² / EI) ~ 1e-4 here."""
    depth = 1e-4
    closed = 3 * 0.08 * depth / (LENGTH ** 3 * np.cos(BETA)) / \
        (np.cos(BETA) - sense * mu * np.sin(BETA))
    for model in (solve_planar, solve_spatial):
        assert model("uniform", depth, mu)[0] == pytest.approx(closed, rel=1e-3)


@pytest.mark.parametrize("angle", [0.7, -1.9])
def test_a_round_finger_presses_the_same_whichever_way_the_belt_lies_about_it(angle):
    """Turning belt and sliding about the axis of a round uniform finger turns
    the solution with them: the same normal force, the tip turned (to 1e-8
    relative)."""
    turn = rot_x(angle)
    force, tip = solve_spatial("uniform", 7.3e-3, MU)
    f, p = solve_spatial("uniform", 7.3e-3, MU, turn)
    assert f == pytest.approx(force, rel=1e-8)
    np.testing.assert_allclose(p, turn @ tip, atol=1e-9)


#: the belt in the spatial finger's frame with the straight tip 7.3 mm below it
PRESSED_BELT = Plane(np.array([*NORMAL, 0.0]), belt_offset(7.3e-3))


def pressing_bird(height: float) -> Quadric:
    """The ellipsoid of :func:`pressing_sweep` (semi-axes 50, 40 and 60 mm)
    with its centre ``height`` (m) above the finger's base line."""
    return Quadric(np.array([0.10, height, 0.0]),
                   np.diag([1 / 0.05 ** 2, 1 / 0.04 ** 2, 1 / 0.06 ** 2]))


def pressing_sweep(model: str):
    """A bird (ellipse/ellipsoid of semi-axes 50 and 40 mm, 60 mm deep) lowered
    onto the thesis finger resting 7.3 mm deep on the belt, then raised
    again, frictionless: the states along the way."""
    _, planar, spatial = solvers("thesis")
    heights = np.concatenate([np.linspace(0.07, 0.04, 13), np.linspace(0.04, 0.07, 13)[1:]])
    plane = belt_offset(7.3e-3)
    out, state = [], None
    for yc in heights:
        if model == "planar":
            conic = (np.array([0.10, yc]), np.diag([1 / 0.05 ** 2, 1 / 0.04 ** 2]))
            sol, state = planar.solve(conic, 0.0, Plane(NORMAL, plane), planar_law(0.0), state)
            belt = sol.belt_normal_force
        else:
            sol, state = spatial.solve(pressing_bird(yc), FrictionLaw(), PRESSED_BELT,
                                       spatial_law(0.0), state)
            belt = sol.belt_normal_force
        assert sol.converged, sol.message
        out.append((yc, state, sol, belt))
    return out


@pytest.mark.parametrize("model", ["planar", "spatial"])
def test_the_bird_pressing_a_finger_on_the_belt_starts_and_ends_its_contact_where_it_touches(
        model):
    """Lowering the bird onto the finger on the belt: belt alone, then the bird
    inside the span with the tip on the belt, the belt's force rising with the
    bird's; raising it again retraces the same states (frictionless: no
    hysteresis) back to the belt alone."""
    sweep = pressing_sweep(model)
    modes = [s.mode for _, s, _, _ in sweep]
    assert modes[0] == modes[-1] == "belt"
    assert "interior+belt" in modes
    down, up = sweep[:13], sweep[12:][::-1]
    for (_, s1, sol1, b1), (_, s2, sol2, b2) in zip(down, up):
        assert s1.mode == s2.mode
        assert b1 == pytest.approx(b2, rel=1e-6, abs=1e-9)
    touching = [(sol.normal_force if model == "spatial" else sol.force, b)
                for _, s, sol, b in down if s.mode == "interior+belt"]
    assert all(b2 > b1 for (_, b1), (_, b2) in zip(touching, touching[1:]))


def two_load_reference(finger: Finger, arc: float, f_bird: np.ndarray, f_belt: np.ndarray):
    """The planar elastica under a force f_bird at arc length ``arc`` and f_belt
    at the tip (forces on the finger, N), by solve_bvp on [0, l] with the
    internal force jumping at ``arc`` (two stacked intervals)."""
    ei = finger.stiffness.ei

    def rhs(u, y):
        # y: x, y, ψ, M on [0, arc] (first 4) and on [arc, l] (last 4), u in [0, 1]
        out = []
        for k, (start, span, force) in enumerate(((0.0, arc, f_bird + f_belt),
                                                  (arc, LENGTH - arc, f_belt))):
            x, yy, psi, m = y[4 * k:4 * k + 4]
            out += [span * np.cos(psi), span * np.sin(psi), span * m / ei(start + span * u),
                    span * (force[0] * np.sin(psi) - force[1] * np.cos(psi))]
        return np.vstack(out)

    def bc(ya, yb):
        return np.array([ya[0], ya[1], ya[2], *(yb[:4] - ya[4:]), yb[7]])

    u = np.linspace(0.0, 1.0, 41)
    sol = solve_bvp(rhs, bc, u, np.zeros((8, u.size)), tol=1e-10, max_nodes=100000)
    assert sol.status == 0, sol.message
    return sol.y[:2, -1], sol.y[4:6, -1]


def test_two_segments_bend_as_the_elastica_under_both_forces():
    """At the deepest state of the planar sweep (bird inside the span, tip on
    the belt): the elastica under the two solved forces, integrated by
    solve_bvp, puts the bird's contact point and the tip where the toolkit's
    two collocated segments do (1e-7 m), and the contact conditions hold:
    the point on the bird's ellipse, the tip on the belt (1e-9)."""
    finger, planar, _ = solvers("thesis")
    yc, state, sol, _ = pressing_sweep("planar")[12]
    assert state.mode == "interior+belt"
    f_bird = -sol.force_on_object_finger_frame
    f_belt = -sol.belt_force
    point, tip = two_load_reference(finger, sol.arc_length, f_bird, f_belt)
    np.testing.assert_allclose(sol.point, point, atol=1e-7)
    np.testing.assert_allclose(sol.belt_point, tip, atol=1e-7)
    d = np.asarray(sol.point) - np.array([0.10, yc])
    assert (d[0] / 0.05) ** 2 + (d[1] / 0.04) ** 2 == pytest.approx(1.0, abs=1e-9)
    assert NORMAL @ sol.belt_point == pytest.approx(belt_offset(7.3e-3), abs=1e-9)


def test_a_finger_clear_of_the_belt_is_left_alone():
    """A belt below the straight tip: no contact, no force, the straight finger."""
    _, planar, spatial = solvers("thesis")
    sol, state = spatial.solve(None, FrictionLaw(), Plane(np.array([*NORMAL, 0.0]),
                                                           belt_offset(-1e-3)), spatial_law(MU))
    assert state.mode == "free" and sol.belt_normal_force == 0.0 and sol.below_belt == 0.0
    sol, state = planar.solve(None, 0.0, Plane(NORMAL, belt_offset(-1e-3)), planar_law(MU))
    assert state.mode == "free" and sol.belt_normal_force == 0.0


def test_a_continued_state_is_the_fresh_one():
    """Continuing the finger on the belt from a neighbouring belt position or
    solving it afresh gives the same state (1e-10 relative)."""
    _, _, spatial = solvers("thesis")
    plane = Plane(np.array([*NORMAL, 0.0]), belt_offset(7.3e-3))
    _, near = spatial.solve(None, FrictionLaw(), Plane(plane.normal, belt_offset(6e-3)),
                            spatial_law(MU))
    continued, _ = spatial.solve(None, FrictionLaw(), plane, spatial_law(MU), near)
    fresh, _ = spatial.solve(None, FrictionLaw(), plane, spatial_law(MU))
    assert isinstance(near, Belted)
    assert continued.belt_normal_force == pytest.approx(fresh.belt_normal_force, rel=1e-10)


def test_a_bird_between_the_finger_s_nodes_is_touched():
    """The spatial finger on the belt, three intervals as the chapter V runs
    mesh it (its nodes up to 31 mm apart), and a ball that dips between two
    nodes, half as deep as it could without reaching them: the finger touches
    the ball where it enters it, continued from the finger on the belt or
    afresh, rather than passing through it."""
    finger = Finger(LENGTH, thesis_finger().stiffness)
    spatial = SpatialBeltContact(SpatialContact(finger, intervals=3))
    plane = Plane(np.array([*NORMAL, 0.0]), belt_offset(7.3e-3))
    on_belt, resting = spatial.solve(None, FrictionLaw(), plane, spatial_law(MU))
    pts = on_belt.shape_points
    gaps = np.linalg.norm(np.diff(pts, axis=1), axis=0)
    k = int(np.argmax(gaps))
    chord = (pts[:, k + 1] - pts[:, k]) / gaps[k]
    radius = 0.05
    dip = 0.5 * (gaps[k] / 2) ** 2 / (2 * radius)
    centre = 0.5 * (pts[:, k] + pts[:, k + 1]) + (radius - dip) * np.cross([0, 0, 1.0], chord)
    ball = Quadric(centre, np.eye(3) / radius ** 2)
    assert ball.level(pts).min() > 0.0
    for previous in (resting, None):
        sol, state = spatial.solve(ball, FrictionLaw(), plane, spatial_law(MU), previous)
        assert sol.converged and state.mode == "interior+belt", sol.message
        assert sol.normal_force > 0.0 and sol.belt_normal_force > 0.0
        assert sol.arc_length == pytest.approx(LENGTH * 0.7, abs=0.02)


def test_a_state_s_depth_into_the_bird_is_its_own_however_often_asked():
    """A finger on the belt keeps the depth into the bird of the last states
    it was asked about; a state with the same bird, belt and laws but
    another shape (the finger's pressed 3 mm into the belt instead of
    7.3 mm) gets its own depth, the one a new solver finds, and the first
    state's is still its own when asked again."""
    finger, _, spatial = solvers("thesis")
    law = spatial_law(MU)
    resting, shallow = (spatial.solve(None, FrictionLaw(), Plane(np.array([*NORMAL, 0.0]),
                                                                 belt_offset(depth)), law)[1]
                        for depth in (7.3e-3, 3e-3))
    ball = Quadric(np.array([0.7 * LENGTH, 0.06, 0.0]), np.eye(3) / 0.05 ** 2)
    near = replace(resting, bird=ball.params)
    moved = replace(near, z=shallow.z)
    fresh = SpatialBeltContact(SpatialContact(finger, intervals=8))
    depths = [spatial.depth(s, "bird") for s in (near, moved, near)]
    assert depths == [fresh.depth(s, "bird") for s in (near, moved, near)]
    assert depths[0] != depths[1]


def test_the_deepest_point_of_a_straight_finger_is_found_between_its_nodes():
    """A straight centreline with nodes at its ends and a circle of radius r
    dipping d below it at 40 % of its length: the lowest level ((r - d) / r)²
    - 1 at that place, where the nodes both lie outside the circle."""
    length, r, d = 0.15, 0.05, 2e-3
    points = np.array([[0.0, length], [0.0, 0.0]])
    tangents = np.array([[1.0, 1.0], [0.0, 0.0]])
    center = np.array([0.4 * length, r - d])
    found = deepest(points, tangents, center, np.eye(2) / r ** 2)
    assert found.level == pytest.approx(((r - d) / r) ** 2 - 1, rel=1e-12)
    assert found.fraction == pytest.approx(0.4, abs=1e-12)
    np.testing.assert_allclose(found.point, [0.4 * length, 0.0], atol=1e-15)
    np.testing.assert_allclose(found.tangent, [1.0, 0.0], atol=1e-15)
    assert np.min(np.sum((points - center[:, None]) ** 2, axis=0)) > r ** 2



def test_the_deepest_point_just_before_a_node_does_not_depend_on_round_off():
    """A straight centreline with eleven nodes 10 mm apart and a circle dipping
    below it at 49.9 mm, 0.1 mm before the sixth node: the grid's least
    value is at that node, where the two gaps that meet give values equal
    up to round-off. Whichever round-off makes the lower, the deepest point
    is the circle's (0.499 of the length, level ((r - d) / r)² - 1), for
    centres moved by a few units in the last place."""
    r, d = 0.05, 2e-3
    points = np.array([np.linspace(0.0, 0.1, 11), np.zeros(11)])
    tangents = np.array([np.ones(11), np.zeros(11)])
    for k in range(-8, 9):
        center = np.array([0.0499 * (1 + k * 2e-16), r - d])
        found = deepest(points, tangents, center, np.eye(2) / r ** 2)
        assert found.level == pytest.approx(((r - d) / r) ** 2 - 1, rel=1e-12)
        assert found.fraction == pytest.approx(0.499, abs=1e-12)


def test_the_deepest_point_of_a_bent_finger_is_the_hermite_curve_s():
    """Four points on a circular arc (radius 0.2 m) with their tangents and
    an ellipse (50 x 30 mm, turned 0.3 rad) dipping about 1 mm below the arc
    30 % into the second gap: the level and place are those of scipy's
    CubicHermiteSpline through the same points and tangents, sampled at
    2e5 points (to 1e-9 in level, 1e-5 of the length)."""
    from scipy.interpolate import CubicHermiteSpline

    angles = np.array([0.0, 0.25, 0.5, 0.75])
    points = 0.2 * np.array([np.sin(angles), 1.0 - np.cos(angles)])
    tangents = np.array([np.cos(angles), np.sin(angles)])
    chords = np.linalg.norm(np.diff(points, axis=1), axis=0)
    t = np.concatenate([[0.0], np.cumsum(chords)])
    curve = CubicHermiteSpline(t, points.T, tangents.T)
    place = t[1] + 0.3 * chords[1]
    turn = np.array([[np.cos(0.3), -np.sin(0.3)], [np.sin(0.3), np.cos(0.3)]])
    matrix = turn @ np.diag([1 / 0.05 ** 2, 1 / 0.03 ** 2]) @ turn.T
    normal = np.array([-curve(place, 1)[1], curve(place, 1)[0]])
    centre = curve(place) - normal / np.linalg.norm(normal) * (0.03 - 1e-3)
    found = deepest(points, tangents, centre, matrix)
    dense = np.linspace(0.0, t[-1], 200001)
    d = curve(dense) - centre
    levels = np.einsum("ni,ij,nj->n", d, matrix, d) - 1.0
    assert found.level == pytest.approx(levels.min(), abs=1e-9)
    assert found.fraction == pytest.approx(dense[np.argmin(levels)] / t[-1], abs=1e-5)
    np.testing.assert_allclose(found.point, curve(dense[np.argmin(levels)]), atol=1e-5)


def test_the_planar_finger_on_the_belt_touches_a_bird_between_its_nodes():
    """The planar counterpart of the spatial test above: the thesis finger on
    the belt, meshed with three intervals, and a disc dipping half as deep
    as it could between the two nodes farthest apart without reaching them:
    the finger touches it inside its span, continued or afresh."""
    finger = Finger(LENGTH, thesis_finger().stiffness)
    planar = PlanarBeltContact(RobustContact(finger, MU, intervals=3))
    plane = Plane(NORMAL, belt_offset(7.3e-3))
    on_belt, resting = planar.solve(None, 0.0, plane, planar_law(MU))
    pts = np.vstack([on_belt.shape_x, on_belt.shape_y])
    gaps = np.linalg.norm(np.diff(pts, axis=1), axis=0)
    k = int(np.argmax(gaps))
    chord = (pts[:, k + 1] - pts[:, k]) / gaps[k]
    radius = 0.05
    dip = 0.5 * (gaps[k] / 2) ** 2 / (2 * radius)
    centre = 0.5 * (pts[:, k] + pts[:, k + 1]) + (radius - dip) * np.array([-chord[1], chord[0]])
    disc = (centre, np.eye(2) / radius ** 2)
    assert np.min(np.sum((pts - centre[:, None]) ** 2, axis=0)) > radius ** 2
    for previous in (resting, None):
        sol, state = planar.solve(disc, 0.0, plane, planar_law(MU), previous)
        assert sol.converged and state.mode == "interior+belt", sol.message
        assert sol.force > 0.0 and sol.belt_normal_force > 0.0
        # touching it, the finger is nowhere inside it (what a grazing check asks)
        assert -1e-9 < planar.depth(state, "bird") <= 1e-9
    # and so with the belt out of reach, in the bird's mode alone
    pressing = (np.array([0.1, radius - 2e-3]), disc[1])
    sol, state = planar.solve(pressing, 0.0, Plane(NORMAL, belt_offset(-0.05)), planar_law(MU))
    assert sol.converged and state.mode == "interior", sol.message
    assert -1e-9 < planar.depth(state, "bird") <= 1e-9


class _Scripted(BeltedContact):
    """A continuation whose Newton solves return their start and whose events
    follow a script: the bird touched, then the touch pulling on the bird."""

    def __init__(self, events):
        super().__init__()
        self.events = list(events)

    def _newton(self, state):
        return state

    def depth(self, state, kind):
        return 0.0

    def event(self, state):
        return self.events.pop(0) if self.events else None

    def switch(self, state, kind):
        return replace(state, mode=kind)


def test_a_first_touch_that_pulls_grazes_and_one_that_pulls_again_fails_the_step():
    """A finger reaching the bird switches into contact; if that contact would
    pull (its force negative), the step ends at the touch, the finger still
    free and grazing: it may enter the bird by GRAZE_DEPTH before a contact
    is tried again. A finger
    already grazing whose touch pulls again has no contact to follow: the
    step fails (None) and is shortened, rather than grazing deeper."""
    free = Belted("free", None, np.zeros(3), np.zeros(2), Plane(np.array([0.0, 1.0]), 0.0),
                  np.zeros(2))
    script = [("bird", 0.0), ("release-bird", 0.0)]
    grazed = _Scripted(script)._step(free, free, 1.0)
    assert grazed.mode == "free" and grazed.graze == GRAZE_DEPTH
    again = replace(free, graze=GRAZE_DEPTH)
    assert _Scripted(script)._step(again, again, 1.0) is None


class _Line(BeltedContact):
    """A continuation along one parameter p (the bird's first entry): the
    bird touches the finger at p = 0.3 and every solve succeeds; the
    parameters of each solve are kept."""

    TOUCH = 0.3
    n_bird = 1

    def __init__(self):
        super().__init__()
        self.solved_at = []

    def _newton(self, state):
        self.solved_at.append(float(state.bird[0]))
        return state

    def depth(self, state, kind):
        return state.bird[0] - self.TOUCH if kind == "bird" else -1.0

    def event(self, state):
        if state.mode == "belt" and self.depth(state, "bird") > 0.0:
            return "bird", self.depth(state, "bird")
        return None

    def switch(self, state, kind):
        return replace(state, mode="interior+belt")


def line_state(p: float, friction: float = 0.0) -> Belted:
    return Belted("belt", np.zeros(1), np.array([p]), np.array([friction]),
                  Plane(np.array([0.0, 1.0]), 0.0), np.zeros(1))


def test_past_a_located_contact_the_rest_of_the_step_is_taken_at_once():
    """A contact starting inside a continuation step is located (within
    EVENT_DEPTH of where it starts), the finger switched into it there, and
    the rest of the step then taken in one solve, as the step itself was
    first tried: the short steps that located the contact were the event's,
    not the path's."""
    line = _Line()
    state, msg = line._path(line_state(0.0), line._params(line_state(1.0)), exact=True)
    assert state.mode == "interior+belt" and state.bird[0] == 1.0 and msg == ""
    touch = [p for p in line.solved_at if 0.0 < p - line.TOUCH <= EVENT_DEPTH]
    assert touch, "the contact is located where it starts"
    after = line.solved_at[line.solved_at.index(touch[0]) + 1:]
    assert after == [touch[0], 1.0]     # the switched solve at the touch, then the rest


def test_a_step_a_contact_starts_in_moves_the_friction_with_the_bird():
    """When a contact starts inside the whole step (not a failed solve), the
    step is continued on its own path, the friction law moving with the bird,
    not the bird under the old law first: no solve combines the bird's new
    place with the old law."""
    line = _Line()
    state, _ = line._follow(line_state(0.0, friction=0.0), line_state(1.0, friction=0.4))
    assert state.mode == "interior+belt" and state.friction[0] == 0.4
    assert line.solved_at[-1] == 1.0
    assert line.solved_at.count(1.0) == 2    # the whole step tried, then the path's last


def test_a_rod_state_split_where_the_bird_touches_and_joined_again_is_itself():
    """Switching a finger on the belt into contact with the bird splits its
    rod state at the touch, u = L / l, into two segments (the second in the
    first's end frame); the release joins them. For a state polynomial in u
    of the collocation's degree (frame and moments quartics) both are
    exact: the join of the split is the state (1e-13)."""
    _, _, spatial = solvers("thesis")
    nodes = _nodes(spatial.contact.widths, spatial.tau)
    # frame and moments quartics in u (the split's rotations are linear in them)
    coefficients = np.random.default_rng(5).normal(size=(7, 5))
    coefficients[0, 0] += 3.0                    # the frame near the identity
    w = (coefficients @ nodes ** np.arange(5)[:, None]).T.ravel()
    for u in (0.23, 0.5, 0.81):
        first, second = spatial._split(w, u)
        np.testing.assert_allclose(spatial._join(first, second, u), w, atol=1e-13)


def test_a_switch_into_a_mode_reuses_its_latest_jacobian():
    """As a simulation's trial evaluations do, the finger resting on the belt
    is continued from one belt-only state into the bird three times, the bird
    a few micrometres apart: the first switch into interior+belt needs a
    Newton solve, the later ones none (the chord method with that mode's
    latest Jacobian factors), and each contact is a fresh solver's to 1e-11 N
    (both stop at residuals of 1e-12, which leaves the roots found from
    different factors about 1e-12 N apart; another equilibrium lies far off)."""
    finger = Finger(LENGTH, thesis_finger().stiffness)

    def resting(solver: SpatialBeltContact) -> Belted:
        _, state = solver.solve(pressing_bird(0.07), FrictionLaw(), PRESSED_BELT,
                                spatial_law(0.0))
        assert state.mode == "belt"
        return state

    solver = SpatialBeltContact(SpatialContact(finger, intervals=8))
    start = resting(solver)
    for height, newton in ((0.042, 1), (0.042 - 1e-6, 0), (0.042 - 2e-5, 0)):
        before = solver.newton_total
        sol, state = solver.solve(pressing_bird(height), FrictionLaw(), PRESSED_BELT,
                                  spatial_law(0.0), start)
        assert state.mode == "interior+belt" and solver.newton_total - before == newton
        fresh = SpatialBeltContact(SpatialContact(finger, intervals=8))
        alone, _ = fresh.solve(pressing_bird(height), FrictionLaw(), PRESSED_BELT,
                               spatial_law(0.0), resting(fresh))
        assert sol.normal_force == pytest.approx(alone.normal_force, abs=1e-11)
        assert sol.belt_normal_force == pytest.approx(alone.belt_normal_force, abs=1e-11)


def fold_case():
    """Finger 5a of the football scene (Table 5-1's lower finger, 152 mm, the
    rod on 3 intervals as the scene meshes it) pressing the ball onto the
    belt at an accepted instant 1.3475 s into the run, and a trial 0.1 ms
    later past the fold where that contact ends (tests/data/football_fold.npz,
    saved from the run): a fresh solver, the accepted state (with the
    Jacobian factors its commit keeps) and the trial's bird, laws and belt."""
    d = np.load(Path(__file__).parent / "data" / "football_fold.npz")
    finger = next(gf.finger for gf in football_setup().grasper.fingers if gf.name == "5a")
    belted = SpatialBeltContact(SpatialContact(finger, intervals=3))
    previous = belted.with_lu(Belted(
        str(d["mode"]), d["z"], d["bird"], d["pfriction"], Plane.from_params(d["pplane"]),
        d["pbelt"], d["post"], float(d["held"]), int(d["side"]), graze=float(d["graze"])))
    target = (Quadric.from_params(d["quadric"]), law(d["friction"]), Plane.from_params(d["plane"]),
              law(d["belt"]))
    return belted, previous, target


def law(p: np.ndarray) -> FrictionLaw:
    """The friction law of the parameters ``FrictionLaw.params``."""
    return FrictionLaw(given=p[:3], mu=p[3], speed=p[4], sliding_at_origin=p[5:8],
                       sliding_gradient=p[8:].reshape(3, 3))


def test_a_trial_past_a_fold_finds_at_its_coarser_stall_what_the_accepted_instant_finds():
    """Past the fold the continued equilibrium ends: a trial, at the TRIAL
    pace (its step whole, lost where Newton cannot take it), and the
    accepted instant, at the COMMIT pace (halved, stalled at 1e-7), both
    lose it and find the same state afresh (the finger off the ball, on the
    belt: 1e-9 N), the trial for under a tenth of the Newton solves (the
    commit creeps up to the fold: 51 against 4)."""
    found = []
    for trial in (True, False):
        belted, previous, target = fold_case()
        sol, state = belted.solve(*target, previous=previous, detail=False, trial=trial)
        assert sol.converged and sol.extras["continuation_lost"], sol.message
        found.append((sol, state, belted.newton_total))
    (trial, t_state, t_cost), (commit, c_state, c_cost) = found
    assert t_state.mode == c_state.mode == "belt"
    assert trial.belt_normal_force == pytest.approx(commit.belt_normal_force, abs=1e-9)
    assert t_cost < c_cost / 10


def test_a_trial_short_of_the_fold_follows_the_continued_equilibrium():
    """Halfway to the trial past the fold, both stalls follow the ball: the
    same state (1e-9 N), nothing lost."""
    belted, previous, target = fold_case()
    quadric = Quadric.from_params((previous.bird + target[0].params) / 2)
    sols = [belted.solve(quadric, *target[1:], previous=previous, detail=False, trial=trial)[0]
            for trial in (True, False)]
    assert not any(s.extras["continuation_lost"] for s in sols)
    assert sols[0].normal_force > 0.0
    assert sols[0].normal_force == pytest.approx(sols[1].normal_force, abs=1e-9)
