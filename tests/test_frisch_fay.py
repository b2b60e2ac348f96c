"""Frisch-Fay closed form: literature values, precision, branches, speed of the sweep."""

import numpy as np
import pytest

from design.errors import MethodUnsupportedError
from design.physics.beam import Finger, PointLoad
from design.physics.stiffness import UniformEI
from design.solvers.beam import solve_beam
from design.solvers.beam.frisch_fay import kl_of, secondary_threshold, solve_root
from tests.problems import table_2_3

UNIT = Finger(1.0, UniformEI(1.0))


@pytest.mark.parametrize("load, y_over_l, dx_over_l", [
    # Tip-loaded cantilever, P L^2/EI = 1, 2, 3, 10 (Bisshopp & Drucker 1945,
    # as tabulated in texts on large-deflection cantilevers; 4-5 digits).
    (1.0, 0.30172, 0.05643), (2.0, 0.49346, 0.16064), (3.0, 0.60325, 0.25442),
    (10.0, 0.81061, 0.55500)])
def test_transverse_tip_load_matches_literature(load, y_over_l, dx_over_l):
    sol = solve_beam(UNIT, [PointLoad(load, np.pi / 2, 1.0)], "frisch-fay")[0]
    # the literature gives 5 decimals: agreement to half a unit in the last
    assert sol.y[-1] == pytest.approx(y_over_l, abs=6e-6)
    assert 1 - sol.x[-1] == pytest.approx(dx_over_l, abs=6e-6)


def test_root_is_exact_to_rounding_over_the_whole_load_range():
    """kL from 1e-7 to 31.6 (F L^2/EI from 1e-14 to 1e3), α over (0, π)."""
    rng = np.random.default_rng(1)
    kl = np.sqrt(np.logspace(-14, 3, 4000))
    alpha = rng.uniform(1e-6, np.pi - 1e-6, kl.size)
    d, psi0, _, its = solve_root(kl, alpha)
    resid = kl_of(alpha, d, psi0)[0] - kl
    # the unknown is carried as ln(min(ψ0, d)): full relative precision, so
    # kL is reproduced to a few eps
    assert np.max(np.abs(resid / kl)) < 1e-13
    assert np.all(d + psi0 == pytest.approx(np.pi - alpha, abs=1e-15))
    assert its.max() <= 40


def test_no_load_and_pure_tension_are_straight():
    sols = solve_beam(UNIT, [PointLoad(0.0, 1.0, 1.0), PointLoad(5.0, np.pi, 1.0)], "frisch-fay")
    for sol in sols:
        assert sol.branch == "straight" and np.all(sol.y == 0) and sol.x[-1] == 1.0


def test_axial_compression_buckles_beyond_euler_load():
    """α = 0: straight for kL ≤ π/2, buckled (+y by convention) beyond."""
    below, above = solve_beam(UNIT, [PointLoad(0.99 * np.pi ** 2 / 4, 0.0, 1.0),
                                     PointLoad(1.5 * np.pi ** 2 / 4, 0.0, 1.0)], "frisch-fay")
    assert below.branch == "straight" and below.y[-1] == 0.0
    assert above.branch == "buckled+" and above.y[-1] > 0.1
    assert above.multiple_equilibria  # the mirror image is an equilibrium too
    assert above.base_moment_error() < 1e-12


def test_model_md_branch_pair_and_secondary_threshold():
    """MODEL.md §2.1: F = 40 N, α = 30°, L = 0.1 m, EI = 0.08 has ψ0 ≈ 110.6° (+y)
    and a second equilibrium bent to -y (ψ0 ≈ -90°): kL = 2.236 exceeds the
    fold at which the reverse branch appears."""
    f = Finger(0.2, UniformEI(0.08))
    sol = solve_beam(f, [PointLoad(40.0, np.radians(30), 0.1)], "frisch-fay")[0]
    assert np.degrees(sol.psi[-1]) == pytest.approx(110.6, abs=0.05)
    assert sol.branch == "primary" and sol.multiple_equilibria
    # the -y branch with ψ0 = -90° is the mirrored primary of α = -30°, p = sin(30°):
    # its kL = K(1/2) + F(asin(sin 15° / (1/2)) | 1/2) must equal 2.236 to 3 digits
    from scipy import special
    p = 0.5
    kl_back = special.ellipk(p * p) + special.ellipkinc(np.arcsin(np.sin(np.radians(15)) / p), p * p)
    assert kl_back == pytest.approx(np.sqrt(40 / 0.08) * 0.1, abs=3e-3)
    assert secondary_threshold(np.array([np.radians(30)]))[0] <= kl_back
    # a transverse load of the same size has one equilibrium only
    single = solve_beam(f, [PointLoad(40.0, np.pi / 2, 0.1)], "frisch-fay")[0]
    assert not single.multiple_equilibria


def test_mirror_symmetry_in_alpha():
    a, b = solve_beam(UNIT, [PointLoad(2.0, 0.7, 1.0), PointLoad(2.0, -0.7, 1.0)], "frisch-fay")
    np.testing.assert_allclose(a.x, b.x, atol=1e-15)
    np.testing.assert_allclose(a.y, -b.y, atol=1e-15)
    np.testing.assert_allclose(a.moment, -b.moment, atol=1e-15)


def test_refuses_non_uniform_finger():
    finger, load = table_2_3()
    with pytest.raises(MethodUnsupportedError, match="uniform EI"):
        solve_beam(finger, [load], "frisch-fay")


def test_shape_satisfies_the_elastica():
    """The closed-form shape, not only its tip: slope, curvature and moment are
    consistent along the beam (x' = cos ψ, y' = sin ψ, EI ψ' = M from statics)."""
    f = Finger(0.3, UniformEI(0.08))
    load = PointLoad(12.0, 1.1, 0.25)
    sol = solve_beam(f, [load], "frisch-fay", nodes=2001)[0]
    ds = np.diff(sol.s)
    mid = (sol.psi[1:] + sol.psi[:-1]) / 2
    # midpoint rule on 2000 intervals: O(h^2 ψ'^2) ≈ 1e-9 relative
    np.testing.assert_allclose(np.diff(sol.x) / ds, np.cos(mid), atol=1e-6)
    np.testing.assert_allclose(np.diff(sol.y) / ds, np.sin(mid), atol=1e-6)
    fx, fy = load.components
    statics = (sol.x[-1] - sol.x) * fy - (sol.y[-1] - sol.y) * fx
    np.testing.assert_allclose(sol.moment, statics, atol=1e-12)
