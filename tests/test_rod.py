"""The finger as a spatial rod (design/physics/rod.py, design/solvers/beam/rod.py):
closed forms, the planar elastica as a special case, convergence order and
equilibrium."""

import numpy as np
import pytest

from design.physics.beam import Finger, PointLoad
from design.physics.stiffness import UniformEI
from design.solvers.beam import solve_beam
from design.solvers.beam.frisch_fay import FrischFay
from design.solvers.beam.rod import solve_rod
from tests.problems import thesis_finger, uniform_finger


def rotated_force(F, alpha, beta):
    """F(-cos α, sin α) in the plane turned by β about the finger's axis."""
    return F * np.array([-np.cos(alpha), np.sin(alpha) * np.cos(beta),
                         np.sin(alpha) * np.sin(beta)])


@pytest.mark.parametrize("beta", [0.0, 0.6, np.pi / 2, 2.5])
@pytest.mark.parametrize("alpha", [np.pi / 2, 1.2, 2.4])
def test_a_round_rod_bends_in_the_plane_of_the_force(alpha, beta):
    """A round uniform rod (EI equal about both axes) under a point force bends
    in the plane of its axis and the force: its load point is Frisch-Fay's
    elliptic-integral solution (eqs. 2.9-2.12) turned by β. Tolerance 1e-9 m:
    the collocation error at K = 8 is below 1e-12 m (next test), Frisch-Fay
    exact to ~1e-15 m."""
    finger, at, F = uniform_finger(0.08, 0.1), 0.1, 15.0
    rod = solve_rod(finger, rotated_force(F, alpha, beta), at)
    x, y, _ = FrischFay(finger, nodes=2).solve([PointLoad(F, alpha, at)])[0].tip
    assert rod.converged
    np.testing.assert_allclose(rod.tip, [x, y * np.cos(beta), y * np.sin(beta)], atol=1e-9)


def test_collocation_converges_at_order_2d():
    """Gauss-Legendre collocation of degree d = 4: interval-end values converge
    at order 2d = 8; measured from K = 3, 6 (asymptotic range) it must exceed 7."""
    finger, at = uniform_finger(0.08, 0.1), 0.1
    force = rotated_force(15.0, 1.2, 0.6)
    x, y, _ = FrischFay(finger, nodes=2).solve([PointLoad(15.0, 1.2, at)])[0].tip
    exact = np.array([x, y * np.cos(0.6), y * np.sin(0.6)])
    errors = [np.linalg.norm(solve_rod(finger, force, at, intervals=k).tip - exact)
              for k in (3, 6)]
    assert np.log2(errors[0] / errors[1]) > 7


def test_the_planar_elastica_is_the_in_plane_special_case():
    """A force in the x-y plane on the thesis's non-uniform finger: the rod stays
    in the plane and its load point is the planar collocation's (both to
    ~1e-12 m; tolerance 1e-9 m)."""
    finger, at = thesis_finger(), 0.0762
    load = PointLoad(15.0, np.pi / 2, at)
    planar = solve_beam(finger, [load], "collocation")[0]
    rod = solve_rod(finger, np.array([*load.components, 0.0]), at)
    np.testing.assert_allclose(rod.tip, [*planar.tip[:2], 0.0], atol=1e-9)


def test_small_loads_follow_linear_theory_about_each_axis():
    """Linear theory (eq. 2.5) about each principal axis: a rod four times
    stiffer about z deflects a quarter as far in z. The load is small
    (tip slope ~1e-3 rad), so the elastica's nonlinearity is below 1e-6
    relative; tolerance 1e-4."""
    L, ei = 0.1, 0.08
    finger = Finger(L, UniformEI(ei), stiff=UniformEI(4 * ei))
    F = np.array([0.0, 0.01, 0.01])
    rod = solve_rod(finger, F, L)
    np.testing.assert_allclose(rod.tip[1:], [F[1] * L ** 3 / (3 * ei),
                                             F[2] * L ** 3 / (3 * 4 * ei)], rtol=1e-4)


@pytest.mark.parametrize("ratio", [1.0, 3.0])
def test_equilibrium_and_unit_quaternions(ratio):
    """The moment at the clamp balances the load (m(0) = r(L) x F) and the
    material frame stays orthonormal, for a large 3-D load on an anisotropic,
    non-uniform finger with twist (to 1e-9 relative)."""
    base = thesis_finger()
    finger = Finger(0.1, base.stiffness, stiff=base.stiffness.scaled(ratio))
    F = np.array([-3.0, 9.0, 6.0])
    rod = solve_rod(finger, F, 0.1)
    assert rod.converged
    np.testing.assert_allclose(rod.moment[:, 0], np.cross(rod.tip, F),
                               atol=1e-9 * np.linalg.norm(F) * 0.1)
    np.testing.assert_allclose(rod.frame.T @ rod.frame, np.eye(3), atol=1e-9)
