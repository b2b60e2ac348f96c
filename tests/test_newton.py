"""The one numpy Newton (design/solvers/newton.py): it converges where it should,
and every way it can fail comes back as a status with a reason."""

import numpy as np
import pytest

from design.solvers.newton import damped_newton, forward_difference


def atan_system(x):
    """r = atan(x), exact root 0: plain Newton from |x0| > 1.39 diverges
    (each step overshoots further), a line search on |r| does not."""
    return np.arctan(x), np.diag(1.0 / (1.0 + x ** 2))


def test_damping_converges_where_plain_newton_diverges():
    damped = damped_newton(atan_system, np.array([3.0]), 1e-12, 50)
    assert damped.converged and damped.message == ""
    assert damped.x[0] == pytest.approx(0.0, abs=1e-12)
    with np.errstate(over="ignore"):
        plain = damped_newton(atan_system, np.array([3.0]), 1e-12, 50, min_damping=1.0)
    # it runs off until the Jacobian 1/(1 + x²) underflows to a singular one
    assert not plain.converged and plain.message == "singular Jacobian"
    assert abs(plain.x[0]) > 1e100


def test_quadratic_convergence_on_a_smooth_system():
    """x² = 2, y = x³: from (1, 1) in a handful of steps (quadratic), to rounding."""
    def fun(z):
        x, y = z
        return np.array([x * x - 2, y - x ** 3]), np.array([[2 * x, 0.0], [-3 * x * x, 1.0]])
    res = damped_newton(fun, np.array([1.0, 1.0]), 1e-14, 20)
    assert res.converged and res.iterations <= 7
    np.testing.assert_allclose(res.x, [np.sqrt(2), 2 * np.sqrt(2)], rtol=1e-15)


def test_forward_difference_jacobian_still_converges():
    """The BDF-4 step's Newton: Jacobian by forward differences (error ~1e-7),
    so linear convergence at rate ~1e-7: a few more steps, same root."""
    res = damped_newton(forward_difference(lambda z: np.array([z[0] ** 2 - 2, z[1] - z[0] ** 3])),
                        np.array([1.0, 1.0]), 1e-13, 20, min_damping=1.0)
    assert res.converged
    np.testing.assert_allclose(res.x, [np.sqrt(2), 2 * np.sqrt(2)], rtol=1e-13)


def test_failures_are_statuses():
    singular = damped_newton(lambda x: (x - 1.0, np.zeros((1, 1))), np.array([0.0]), 1e-12, 10)
    assert not singular.converged and singular.message == "singular Jacobian"
    # no root: x² + 1 = 0 wanders without converging
    wander = damped_newton(lambda x: (x ** 2 + 1, np.diag(2 * x)), np.array([0.5]), 1e-12, 30)
    assert not wander.converged and "did not converge in 30 iterations" in wander.message
    assert wander.iterations == 30 and np.isfinite(wander.x).all()
    # a residual undefined past x = 1, the root at 2: the plain step lands there
    undefined = damped_newton(lambda x: (np.where(x > 1, np.nan, x - 2), np.eye(1)),
                              np.array([0.0]), 1e-12, 10, min_damping=1.0)
    assert not undefined.converged and "non-finite" in undefined.message


def test_residual_tolerance_stops_at_a_small_residual():
    res = damped_newton(atan_system, np.array([0.1]), 0.0, 50, residual_tolerance=1e-6)
    assert res.converged and abs(res.residual[0]) <= 1e-6


def test_a_chord_jacobian_that_is_not_finite_has_no_inverse():
    """A Jacobian with a NaN (here √(z - 2)'s at z = 1) inverts to NaN
    without an error; the chord method must not iterate with it (its caller
    falls back to Newton), and a finite one is inverted."""
    import casadi as ca

    from design.solvers.newton import Chord
    z, q = ca.SX.sym("z", 2), ca.SX.sym("q", 1)
    residual = ca.Function("nan_jacobian", [z, q], [
        ca.vertcat(ca.sqrt(z[0] - 2) + z[1] - q[0], z[1] - q[0])])
    chord = Chord(residual)
    assert chord.inverse(np.array([1.0, 1.0]), np.array([1.0])) is None
    np.testing.assert_allclose(chord.inverse(np.array([6.0, 1.0]), np.array([1.0])),
                               [[4.0, -4.0], [0.0, 1.0]], atol=1e-12)
