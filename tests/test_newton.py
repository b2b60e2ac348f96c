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


def test_a_chord_jacobian_that_is_not_finite_or_singular_has_no_factors():
    """A Jacobian with a NaN (here √(z - 2)'s at z = 1) factors to NaN
    without an error, and a singular one has a zero pivot; the chord method
    must iterate with neither (its caller falls back to Newton). A finite,
    regular one is factored: its factors solve J x = b."""
    import casadi as ca

    from design.solvers.newton import Chord
    z, q = ca.SX.sym("z", 2), ca.SX.sym("q", 1)
    residual = ca.Function("nan_jacobian", [z, q], [
        ca.vertcat(ca.sqrt(z[0] - 2) + z[1] - q[0], (z[0] - 6) * z[1] - q[0])])
    chord = Chord(residual)
    assert chord.factor(np.array([1.0, 1.0]), np.array([1.0])) is None
    assert chord.factor(np.array([6.0, 0.0]), np.array([1.0])) is None     # second row zero
    lu = chord.factor(np.array([6.0, 1.0]), np.array([1.0]))
    # J = [[1/4, 1], [1, 0]] at (6, 1)
    np.testing.assert_allclose(chord.lu_solve(lu, np.array([1.25, 1.0])), [1.0, 1.0], atol=1e-15)


def _cubic_chord():
    """R(z, q) = (z0³ + z0 - q0, z1 - z0 q1): one real root for every q."""
    import casadi as ca

    from design.solvers.newton import Chord
    z, q = ca.SX.sym("z", 2), ca.SX.sym("q", 2)
    return Chord(ca.Function("cubic", [z, q], [ca.vertcat(z[0] ** 3 + z[0] - q[0],
                                                          z[1] - z[0] * q[1])]))


def test_chord_newton_converges_quadratically_and_hands_on_its_factors():
    """Newton from far (z0 = 10 for the root 1 of z³ + z = 2) reaches the
    root to 1e-14 in the iterations undamped Newton needs from there (the
    line search halves no step of this monotone cubic: 10 iterations), and
    the factors it returns let the chord method reach a nearby root."""
    chord = _cubic_chord()
    root = chord.newton(np.array([10.0, 0.0]), np.array([2.0, 3.0]), 1e-14, 30)
    assert root.converged and root.iterations == 10
    np.testing.assert_allclose(root.z, [1.0, 3.0], atol=1e-14)
    # the chord method from there to q0 = 2.01 with the kept factors
    near = chord.solve(root.z, np.array([2.01, 3.0]), root.lu, 1e-14, 30)
    assert near is not None and abs(near[0] ** 3 + near[0] - 2.01) <= 1e-14
    # three iterations are not enough from there: not converged, the third iterate
    short = chord.newton(np.array([10.0, 0.0]), np.array([2.0, 3.0]), 1e-14, 3)
    assert not short.converged and short.iterations == 3 and short.z[0] > 1.5
    # at the root already: no iteration, no factors
    again = chord.newton(root.z, np.array([2.0, 3.0]), 1e-12, 30)
    assert again.converged and again.iterations == 0 and again.lu is None


def test_the_chord_method_takes_the_first_factors_that_converge():
    """Factors taken in turn: those of a far point (z0 = 10's Jacobian, 75
    times the root's slope) do not reach the root to 1e-14 within 12 chord
    iterations; the root's own and those of a point beside it both do, and
    the first of them listed is taken (None skipped); where none converges,
    no root and no factors."""
    chord = _cubic_chord()
    q = np.array([2.01, 3.0])
    root = np.array([1.0, 3.0])
    far = chord.factor(np.array([10.0, 30.0]), q)
    beside, own = chord.factor(root + 0.01, q), chord.factor(root, q)
    assert chord.solve(root, q, far, 1e-14, 12) is None
    for first, second in ((beside, own), (own, beside)):
        z, used = chord.solve_first(root, q, (None, far, first, second), 1e-14, 12)
        assert used is first and abs(z[0] ** 3 + z[0] - 2.01) <= 1e-14
    assert chord.solve_first(root, q, (far, None, far), 1e-14, 12) == (None, None)


def test_chord_newton_gives_up_at_once_where_no_step_reduces_the_residual():
    """z0² + 1 = q0 has no root for q0 = 0.5 (the residual's least value is
    0.5 at z0 = 0): from z0 = 0.1 Newton's steps overshoot past 0 and the
    line search finds no reduction near the minimum, so the solve ends long
    before its 30 iterations, not converged, without a NaN."""
    import casadi as ca

    from design.solvers.newton import Chord
    z, q = ca.SX.sym("z", 1), ca.SX.sym("q", 1)
    chord = Chord(ca.Function("no_root", [z, q], [z ** 2 + 1 - q]))
    root = chord.newton(np.array([0.1]), np.array([0.5]), 1e-12, 30)
    assert not root.converged and root.iterations < 10 and np.all(np.isfinite(root.z))