"""3-D drum and finger frames, the ellipsoid's cuts, the bird's lowest point."""

import numpy as np
import pytest

from design.physics.bird import Bird, BirdDynamics, Legs
from design.physics.kinematics import Drum, Ellipsoid, FingerMount, lowest_point, mirror_frame

DRUM = Drum(spacing=0.368, speed=2.0944, tilt=0.1)
MOUNTS = [FingerMount(np.radians(a), h, r, np.radians(px), np.radians(py))
          for a, h, r, px, py in [(-138.8, 0.095, 0.083, 45, -15), (-150, 0.025, 0.108, -90, 7.5),
                                  (30, 0.05, 0.1, 10, 40)]]


@pytest.mark.parametrize("mount", MOUNTS)
@pytest.mark.parametrize("t", [0.0, 0.37, 1.9])
def test_finger_frames_are_rotations(mount, t):
    base, R = DRUM.frame(mount, t)
    np.testing.assert_allclose(R.T @ R, np.eye(3), atol=1e-14)
    assert np.linalg.det(R) == pytest.approx(1.0)
    # the base is r_D from the (tilted) drum axis, at height h along it
    axis = R[:, 2] if mount.phi_x == mount.phi_y == 0 else DRUM.frame(FingerMount(0, 0, 0), 0)[1][:, 2]
    rel = base - DRUM.origin
    along = rel @ axis
    assert along == pytest.approx(mount.height)
    assert np.linalg.norm(rel - along * axis) == pytest.approx(mount.radius)


def test_left_drum_mirrors_the_right():
    bird = Ellipsoid(0.097, 0.066, 0.057, (0.01, 0.0, 0.06), 0.2)
    for mount in MOUNTS:
        base, R = DRUM.frame(mount, 0.8)
        lb, lR = mirror_frame(base, R)
        assert np.linalg.det(lR) == pytest.approx(1.0)
        np.testing.assert_allclose(lb, base * [1, -1, 1])
        np.testing.assert_allclose(lR[:, 0], R[:, 0] * [1, -1, 1])      # finger axis reflected
        # the left frame's axes are the right's reflected, so a bird symmetric
        # about XZ is the same 2-D problem for both fingers: same ellipse, same
        # side, same contact; only the world force mirrors
        right, left = bird.cut(base, R), bird.cut(lb, lR)
        if right is None:
            assert left is None
            continue
        assert (left.a, left.b, left.theta) == pytest.approx((right.a, right.b, right.theta))
        assert left.center == pytest.approx(right.center)


def test_a_sphere_is_cut_in_a_circle():
    """Radius R at distance d from the plane: circle of radius sqrt(R² - d²)
    centred at the foot of the perpendicular."""
    R0 = 0.06
    sphere = Ellipsoid(R0, R0, R0, (0.2, -0.1, 0.05))
    for mount in MOUNTS:
        base, R = DRUM.frame(mount, 0.3)
        n = R[:, 2]
        d = (np.array(sphere.center) - base) @ n
        cut = sphere.cut(base, R)
        if abs(d) >= R0:
            assert cut is None
            continue
        assert cut.a == pytest.approx(cut.b) == pytest.approx(np.sqrt(R0 ** 2 - d ** 2))
        foot = np.array(sphere.center) - d * n
        np.testing.assert_allclose(base + R[:, :2] @ np.array(cut.center), foot, atol=1e-12)


def test_cut_points_lie_on_the_ellipsoid():
    bird = Ellipsoid(0.097, 0.066, 0.057, (0.0, 0.0, 0.06), -0.3)
    for mount in MOUNTS:
        for t in np.linspace(0, 3, 7):
            base, R = DRUM.frame(mount, t)
            cut = bird.cut(base, R)
            if cut is None:
                continue
            s = np.linspace(0, 2 * np.pi, 13)
            pts = np.array(cut.center)[:, None] + np.array(
                [[np.cos(cut.theta), -np.sin(cut.theta)], [np.sin(cut.theta), np.cos(cut.theta)]]
            ) @ np.stack([cut.a * np.cos(s), cut.b * np.sin(s)])
            world = base[:, None] + R[:, :2] @ pts
            np.testing.assert_allclose(bird.level(world), 0.0, atol=1e-10)


@pytest.mark.parametrize("theta", [0.0, 0.3, -1.0, 1.5])
def test_lowest_point_of_the_pitched_ellipse(theta):
    """MODEL.md §5: D = sqrt(γ² cos²θ + η² sin²θ) below the centre and
    (η² - γ²) sinθ cosθ / D ahead of it (X = x cosθ + z sinθ), by brute force."""
    eta, gamma = 0.097, 0.057
    s = np.linspace(0, 2 * np.pi, 200001)
    x, z = eta * np.cos(s), gamma * np.sin(s)
    X = x * np.cos(theta) + z * np.sin(theta)
    Z = -x * np.sin(theta) + z * np.cos(theta)
    k = np.argmin(Z)
    ahead, D = lowest_point(eta, gamma, theta)
    assert D == pytest.approx(-Z[k], abs=1e-9)
    assert ahead == pytest.approx(X[k], abs=1e-5)


def test_support_derivatives():
    """dD/dθ = x_A (the lowest point is where the ellipse rolls) and D''."""
    dyn = BirdDynamics(Bird(0.097, 0.066, 0.057, 1.8, 0.00417), Legs(), 0.4)
    for theta in [-0.7, 0.1, 0.9]:
        h = 1e-5
        _, D, d1, d2 = dyn.support(theta)
        Dp, Dm = dyn.support(theta + h)[1], dyn.support(theta - h)[1]
        assert d1 == pytest.approx((Dp - Dm) / (2 * h), rel=1e-7)
        assert d2 == pytest.approx((Dp - 2 * D + Dm) / h ** 2, rel=1e-4)


@pytest.mark.parametrize("tilt", [0.0, 0.3])
def test_the_drums_turning_carries_a_finger_frame_in_time(tilt):
    """The simulator and the reach filter turn a finger's frame at t = 0 about
    the drum's (tilted) axis (Drum.turning, for one time and for all at once):
    the same as the finger frame evaluated at each time (1e-12 m, 1e-12)."""
    drum = Drum(0.368, 20 * 2 * np.pi / 60, x=0.01, tilt=tilt)
    mount = FingerMount(angle=1.9, height=0.03, radius=0.108, phi_x=0.7, phi_y=0.26)
    times = np.linspace(0.0, 2.0, 41)
    base0, R0 = drum.frame(mount, 0.0)
    turns = drum.turning(times)
    for k, t in enumerate(times):
        b, R = drum.frame(mount, t)
        np.testing.assert_array_equal(drum.turning(t), turns[k])
        np.testing.assert_allclose(drum.origin + turns[k] @ (base0 - drum.origin), b, atol=1e-12)
        np.testing.assert_allclose(turns[k] @ R0, R, atol=1e-12)


def test_the_straight_fingers_least_level_is_the_sampled_minimum():
    """The grasp's reach test (straight_level, a parabola's closed-form
    minimum) against the level function sampled densely along the finger:
    equal to the sampled minimum within the sampling error (the parabola's
    curvature times half a sample step squared), never above it."""
    from design.solvers.grasp.fingers import straight_level
    rng = np.random.default_rng(7)
    for _ in range(200):
        body = Ellipsoid(*rng.uniform(0.03, 0.15, 3), tuple(rng.uniform(-0.1, 0.1, 3)),
                         rng.uniform(-1.0, 1.0))
        mount = FingerMount(*rng.uniform(-3, 3, 1), *rng.uniform(0.0, 0.1, 1),
                            *rng.uniform(0.05, 0.12, 1), *rng.uniform(-3, 3, 2))
        base, R = DRUM.frame(mount, rng.uniform(0, 1))
        length = rng.uniform(0.05, 0.2)
        x = np.linspace(0.0, length, 20001)
        sampled = body.level(base[:, None] + np.outer(R[:, 0], x))
        curvature = float(R[:, 0] @ body.rotation @ body.matrix @ body.rotation.T @ R[:, 0])
        exact = straight_level(body, base, R[:, 0], length)
        assert exact <= sampled.min() + 1e-12
        assert exact >= sampled.min() - curvature * (x[1] / 2) ** 2 - 1e-12
