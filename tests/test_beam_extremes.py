"""Every beam method at the extremes, each with a defined outcome."""

from dataclasses import replace

import numpy as np
import pytest

from design.physics.beam import Finger, PointLoad
from design.physics.stiffness import UniformEI
from design.solvers.beam import METHODS, solve_beam
from tests.problems import thesis_finger, tip_distance

NUMERICAL = ["shooting", "fdm", "collocation"]
ALL = ["small-deflection", "frisch-fay", *NUMERICAL]


def uniform(ei=0.08, length=0.2):
    return Finger(length, UniformEI(ei))


def agree_with_closed_form(finger, load, method):
    """Solve and compare with Frisch-Fay within the method's own error estimate."""
    ref = solve_beam(finger, [load], "frisch-fay")[0]
    sol = solve_beam(finger, [load], method)[0]
    assert sol.converged, sol.message
    assert sol.branch == ref.branch
    assert tip_distance(sol, ref) <= sol.error_estimate + ref.error_estimate
    return sol, ref


@pytest.mark.parametrize("method", ALL)
def test_zero_load_is_exactly_straight(method):
    sol = solve_beam(uniform(), [PointLoad(0.0, 1.0, 0.15)], method)[0]
    assert sol.converged and sol.branch == "straight"
    assert sol.error_estimate == 0.0 and np.all(sol.y == 0) and sol.x[-1] == 0.15


@pytest.mark.parametrize("method", NUMERICAL + ["frisch-fay"])
@pytest.mark.parametrize("force", [1e-12, 1e-8, 1e-4])
def test_vanishing_load_tends_to_linear_theory(method, force):
    load = PointLoad(force, 1.0, 0.15)
    sol = solve_beam(uniform(), [load], method)[0]
    lin = solve_beam(uniform(), [load], "small-deflection")[0]
    assert sol.converged and sol.branch == "primary"
    # relative difference O((F L^2/EI)) ≤ 3e-5 at F = 1e-4 N
    assert sol.y[-1] == pytest.approx(lin.y[-1], rel=1e-4)


@pytest.mark.parametrize("method", NUMERICAL + ["frisch-fay"])
@pytest.mark.parametrize("kl2", [1e-4, 1e-2, 1.0, 30.0, 1e3])
def test_load_range_kl2_from_1e_4_to_1e3(method, kl2):
    """F L^2/EI over seven decades, transverse and oblique."""
    for alpha in [np.pi / 2, 0.4, 2.5]:
        load = PointLoad(kl2 * 0.08 / 0.15 ** 2, alpha, 0.15)
        if method == "frisch-fay":
            sol = solve_beam(uniform(), [load], method)[0]
            assert sol.converged and sol.base_moment_error() < 1e-10 * (1 + load.force)
        else:
            agree_with_closed_form(uniform(), load, method)


@pytest.mark.parametrize("method", NUMERICAL)
@pytest.mark.parametrize("ei", [1e-4, 1e-2, 1.0, 10.0])
def test_flexural_rigidity_from_1e_4_to_10(method, ei):
    """A 5 N load at 0.1 m: F L^2/EI from 500 (very soft) to 5e-3 (very stiff)."""
    agree_with_closed_form(uniform(ei), PointLoad(5.0, 1.2, 0.1), method)


@pytest.mark.parametrize("method", NUMERICAL)
@pytest.mark.parametrize("scale", [1e-3, 1e2])
def test_very_soft_and_very_stiff_non_uniform_fingers(method, scale):
    """The thesis finger with E scaled by 1e-3 and 1e2: methods still agree."""
    finger = Finger(0.203, thesis_finger().stiffness.scaled(scale))
    load = PointLoad(5.0, 1.2, 0.15)
    sol = solve_beam(finger, [load], method)[0]
    ref = solve_beam(finger, [load], "collocation", nodes=64)[0]
    assert sol.converged and sol.branch == "primary"
    assert tip_distance(sol, ref) <= sol.error_estimate + ref.error_estimate


@pytest.mark.parametrize("method", NUMERICAL + ["frisch-fay", "small-deflection"])
@pytest.mark.parametrize("at", [1e-6, 1e-4, 1e-3])
def test_load_point_near_the_base(method, at):
    load = PointLoad(15.0, np.pi / 2, at)
    sol = solve_beam(uniform(), [load], method)[0]
    assert sol.converged and sol.s[-1] == pytest.approx(at)
    # a 15 N push 1 µm from the clamp: kL = 1.4e-5, deflection F at^3/(3 EI)
    assert sol.y[-1] == pytest.approx(15 * at ** 3 / (3 * 0.08), rel=1e-3)


@pytest.mark.parametrize("method", NUMERICAL)
@pytest.mark.parametrize("alpha", [1e-6, 1e-3, -1e-3])
def test_near_axial_sweep_follows_the_continued_branch(method, alpha):
    """Near-axial compression swept through the buckling load: every solution
    is the primary branch continued from the smaller load (bent to the side
    the small transverse part pushes, equal to the closed form's primary),
    never the reverse-bent equilibrium that exists past the fold, whose
    existence is reported. (The tip moves fast just past the Euler load:
    that is the imperfect pitchfork, not a jump between branches.)"""
    finger = uniform()
    forces = np.linspace(0.5, 40.0, 12)          # kL from 0.5 to 4.5 (Euler: π/2)
    loads = [PointLoad(f, alpha, 0.2) for f in forces]
    sols = solve_beam(finger, loads, method)
    refs = solve_beam(finger, loads, "frisch-fay")
    for sol, ref in zip(sols, refs):
        assert sol.converged and sol.branch == "primary"
        assert np.sign(sol.y[-1]) == np.sign(alpha)
        assert tip_distance(sol, ref) <= sol.error_estimate + ref.error_estimate
    assert sols[-1].multiple_equilibria and not sols[0].multiple_equilibria


@pytest.mark.parametrize("method", NUMERICAL)
def test_exactly_axial_load_buckles_past_euler(method):
    """α = 0: straight below the Euler load; above it the straight state is
    unstable and the buckled shape (+y by convention) is returned and named."""
    finger = uniform()
    euler = np.pi ** 2 * 0.08 / (4 * 0.2 ** 2)
    below, above = solve_beam(finger, [PointLoad(0.9 * euler, 0.0, 0.2),
                                       PointLoad(2.0 * euler, 0.0, 0.2)], method)
    assert below.branch == "straight" and abs(below.y[-1]) < 1e-12
    assert above.branch == "buckled+" and above.y[-1] > 0.05
    ff = solve_beam(finger, [PointLoad(2.0 * euler, 0.0, 0.2)], "frisch-fay")[0]
    assert tip_distance(above, ff) <= above.error_estimate + ff.error_estimate


@pytest.mark.parametrize("method", NUMERICAL)
def test_axial_load_past_euler_without_a_buckled_shape_is_not_converged(method, monkeypatch):
    """If Newton finds no buckled shape past the Euler load, the straight
    state (an unstable equilibrium there) comes back as not converged, with
    the reason (not marked converged, as if it were the only equilibrium),
    and the uniform finger's other equilibrium is reported."""
    cls = METHODS[method]
    solve = cls._solve
    monkeypatch.setattr(cls, "_solve", lambda self, load, guess: replace(
        solve(self, load, guess), converged=False, message="Newton forced to fail"))
    euler = np.pi ** 2 * 0.08 / (4 * 0.2 ** 2)
    sol = solve_beam(uniform(), [PointLoad(2.0 * euler, 0.0, 0.2)], method)[0]
    assert not sol.converged and sol.branch == "straight"
    assert "no buckled equilibrium" in sol.message and "Newton forced to fail" in sol.message
    assert sol.multiple_equilibria is True


@pytest.mark.parametrize("method", NUMERICAL)
@pytest.mark.parametrize("alpha", [np.pi - 1e-6, np.pi - 1e-3, -(np.pi - 1e-3), np.pi])
def test_near_tension(method, alpha):
    sol, _ = agree_with_closed_form(uniform(), PointLoad(20.0, alpha, 0.2), method)
    assert abs(sol.y[-1]) < 1e-3 * 0.2


def test_linear_theory_says_it_ignores_axial_loads():
    sol = solve_beam(uniform(), [PointLoad(100.0, 0.0, 0.2)], "small-deflection")[0]
    assert sol.branch == "straight" and "axial" in sol.message
