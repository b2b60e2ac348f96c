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


def _counting_factors(chord):
    """``chord`` with its factorisations counted (the list's length)."""
    calls, factor = [], chord.factor
    chord.factor = lambda z, q: calls.append(z[0]) or factor(z, q)
    return calls


def test_chord_newton_keeps_its_factors_while_they_converge_fast(monkeypatch):
    """Newton from far (z0 = 10 for the root 1 of z³ + z = 2): undamped
    Newton (no factors kept) takes 10 iterations and 10 Jacobians from there
    (the line search halves no step of this monotone cubic). Keeping the
    factors while a step cuts max |R| tenfold, it factors 8 Jacobians: the
    approach from 10 converges too slowly to keep any, and once at 1 + 4e-5
    the factors there take it to 1e-14 in 4 iterations, 2 more than
    Newton's. The factors it returns let the chord method reach a nearby
    root."""
    import design.solvers.newton as newton_module
    chord = _cubic_chord()
    for keep_below, iterations, jacobians in ((0.0, 10, 10), (0.1, 12, 8)):
        monkeypatch.setattr(newton_module, "KEEP_FACTORS_BELOW", keep_below)
        calls = _counting_factors(chord)
        root = chord.newton(np.array([10.0, 0.0]), np.array([2.0, 3.0]), 1e-14, 30)
        assert root.converged and (root.iterations, len(calls)) == (iterations, jacobians)
        np.testing.assert_allclose(root.z, [1.0, 3.0], atol=1e-14)
        del chord.factor
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

def _coupled_chord():
    """R(z, q) = A z + 0.1 sin(z) - q for a fixed well-conditioned A (11 x 11:
    two passes of four columns and a remainder of three in the compiled
    chord loop's triangular solves)."""
    import casadi as ca

    from design.solvers.newton import Chord
    rng = np.random.default_rng(7)
    a = rng.normal(size=(11, 11)) + 6 * np.eye(11)
    z, q = ca.SX.sym("z", 11), ca.SX.sym("q", 11)
    return Chord(ca.Function("coupled", [z, q], [ca.mtimes(ca.DM(a), z) + 0.1 * ca.sin(z) - q]))


@pytest.mark.skipif(__import__("design.solvers.compiled", fromlist=["compiler"]).compiler()[0]
                    is None, reason="no C compiler: the chord loop runs in Python (tested above)")
def test_the_compiled_chord_loop_finds_the_python_loops_roots():
    """The chord loop compiled with its residual (design/solvers/native_chord.py)
    against the same loop in Python with LAPACK's getrs, from the same start
    with the same factors: both converge or both do not, and their roots
    agree to the tolerance (their triangular solves round differently).
    Both outcomes occur: two iterations are too few, and the cubic's factors
    at z = 5 (a slope 76 times the root's) do not converge within 12."""
    rng = np.random.default_rng(3)
    outcomes = set()
    for chord in (_coupled_chord(), _cubic_chord()):
        assert chord.native is not None
        n = chord.native._z.size
        near, far = (chord.factor(np.full(n, z), np.ones(n)) for z in (0.0, 5.0))
        for _ in range(20):
            z0, q = 0.01 * rng.normal(size=n), rng.normal(size=n)
            for factor, max_iter in ((near, 40), (near, 2), (far, 12)):
                native = chord.solve(z0, q, factor, 1e-13, max_iter)
                kept, chord.native = chord.native, None
                python = chord.solve(z0, q, factor, 1e-13, max_iter)
                chord.native = kept
                assert (native is None) == (python is None)
                outcomes.add(native is None)
                if native is not None:
                    np.testing.assert_allclose(native, python, atol=1e-12)
                    assert np.abs(chord._residual(native, q)[0]).max() <= 1e-13
    assert outcomes == {True, False}
    assert chord.solve(np.zeros(2), np.array([2.0, 3.0]), far, 1e-13, 12) is None


@pytest.mark.skipif(__import__("design.solvers.compiled", fromlist=["compiler"]).compiler()[0]
                    is None, reason="no C compiler: the chord loop runs in Python")
def test_the_compiled_chord_loop_solves_a_linear_system_in_one_update():
    """R(z, q) = A z - q with A's own factors: one chord update is the
    solution, so the compiled loop converges with max_iter = 1 exactly when
    its row swaps and triangular solves are right. A (13 x 13, random normal)
    needs row swaps; 13 columns take three passes of four and one of one."""
    import casadi as ca

    from design.solvers.newton import Chord
    rng = np.random.default_rng(11)
    a = rng.normal(size=(13, 13))
    z, q = ca.SX.sym("z", 13), ca.SX.sym("q", 13)
    chord = Chord(ca.Function("linear13", [z, q], [ca.mtimes(ca.DM(a), z) - q]))
    factor = chord.factor(np.zeros(13), np.zeros(13))
    assert np.any(factor.piv != np.arange(13))             # swaps are exercised
    assert chord.updates == 0
    for k in range(10):
        b = rng.normal(size=13)
        root = chord.solve(np.zeros(13), b, factor, 1e-12 * np.linalg.cond(a), 1)
        assert root is not None and chord.updates == k + 1
        np.testing.assert_allclose(root, np.linalg.solve(a, b), atol=1e-12 * np.linalg.cond(a))


def test_without_a_compiler_the_chord_method_is_the_python_loop(monkeypatch, tmp_path):
    """DESIGN_COMPILE=0: no compiled loop, and the chord method still finds
    the cubic's root from the root's factors."""
    monkeypatch.setenv("DESIGN_COMPILE", "0")
    monkeypatch.setenv("DESIGN_CACHE_DIR", str(tmp_path))
    chord = _cubic_chord()
    assert chord.native is None
    q = np.array([2.01, 3.0])
    z = chord.solve(np.array([1.0, 3.0]), q, chord.factor(np.array([1.0, 3.0]), q), 1e-14, 12)
    assert z is not None and abs(z[0] ** 3 + z[0] - 2.01) <= 1e-14
