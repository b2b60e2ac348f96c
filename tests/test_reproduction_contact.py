"""The thesis's chapter III numbers, reproduced where they are unambiguous
(``design reproduce``'s report.html has the full tables)."""

import numpy as np
import pytest

from design.reproduce.contact import (FEM_PASS, THESIS_CASES, THESIS_PASS, UNIFORM, pass_angle,
                                      pass_position, scene, table_3_1, thesis_pass)
from design.solve.contact import RobustContact


@pytest.fixture(scope="module")
def cases():
    return table_3_1()


@pytest.fixture(scope="module")
def pushed_pass():
    return thesis_pass("push", 18.0)


def test_case_1_uniform_finger_matches_algorithm_one(cases):
    """Table 3-2, Case 1: contact (0.104, 0.045) m, ψ0 = 35.6°, α = 85.39°,
    printed to 3 digits and found to ERR = 0.5 mm; ours (EI = 0.08, the thesis's
    friction convention) within 1 mm and 0.5°. The force is 5.7% lower (see
    the pass test: the thesis's forces are 7% above EI = 0.08 throughout)."""
    sol = cases[(1, "robust, uniform EI = 0.08")]
    point, alpha, force, psi, arc = THESIS_CASES[(1, "Algorithm I")]
    assert np.hypot(*np.subtract(sol.point, point)) < 1e-3
    assert np.degrees(sol.psi) == pytest.approx(psi, abs=0.5)
    assert np.degrees(sol.alpha) == pytest.approx(alpha, abs=0.5)
    assert sol.force / force == pytest.approx(0.943, abs=0.01)


def test_case_2_is_a_pull(cases):
    """Table 3-2, Case 2 (x = 0.0662 m, ψ0 = 74.13°, L = 111.4 mm, F = 18.72 N):
    matched by the pulled finger (y_f = -0.079 as Figure 3-7 shows)."""
    sol = cases[(2, "robust, uniform EI = 0.08")]
    point, _, force, psi, arc = THESIS_CASES[(2, "Algorithm I")]
    assert sol.side == "pull"
    assert sol.point[0] == pytest.approx(point[0], abs=5e-4)
    assert sol.point[1] == pytest.approx(-0.0794, abs=5e-4)
    assert abs(np.degrees(sol.psi)) == pytest.approx(psi, abs=0.2)
    assert sol.arc_length == pytest.approx(arc, abs=5e-4)
    assert sol.force == pytest.approx(force, rel=0.03)


def test_effective_ei_stand_in_gets_the_force_not_the_contact_point(cases):
    """Against a rigid object a uniform finger's contact geometry does not depend
    on EI at all, so the effective-EI stand-in (position-matched to the soft
    finger's contact load) touches where the EI = 0.08 finger does, 15-25 mm
    from the non-uniform finger's contact; only its force comes close (≤ 15%)."""
    for case in (1, 2):
        soft = cases[(case, "robust, non-uniform soft")]
        uniform = cases[(case, "robust, uniform EI = 0.08")]
        stand_in = next(v for k, v in cases.items() if k[0] == case and "effective" in k[1]
                        and "robust" in k[1])
        assert stand_in.converged
        np.testing.assert_allclose(stand_in.point, uniform.point, atol=1e-10)
        assert np.hypot(*np.subtract(stand_in.point, soft.point)) > 0.01
        assert stand_in.force == pytest.approx(soft.force, rel=0.15)


def test_algorithm_two_equals_the_robust_solver_on_the_same_finger(cases):
    """Our implementation of the thesis's Algorithm II converges (N = 155) to the
    robust solver's answer on the non-uniform finger, within the FDM's O(h^2)."""
    for case in (1, 2):
        a = cases[(case, "Algorithm II (thesis), soft, N = 155")]
        r = cases[(case, "robust, non-uniform soft")]
        assert a.converged and a.force == pytest.approx(r.force, rel=1e-3)
        assert np.hypot(*np.subtract(a.point, r.point)) < 1e-4


def test_pass_contact_points_and_forces(pushed_pass):
    """Table 3-5 at every listed φ but 18°: contact points within 1.5 mm (the
    thesis's 3 digits and 0.5 mm tolerance), forces 5-10% below the thesis's
    (a uniform 7% offset, as if its EI were 7% above 0.08)."""
    ratios = []
    for phi, (point, psi, force, _) in THESIS_PASS.items():
        sol = pushed_pass[float(phi)]
        if phi == 18:
            continue
        assert sol.contact and sol.converged
        assert np.hypot(*np.subtract(sol.point, point)) < 1.5e-3
        ratios.append(force / sol.force)
    assert 1.05 <= min(ratios) and max(ratios) <= 1.10
    assert np.std(ratios) < 0.015


def test_pass_end_thesis_contact_lies_beyond_the_finger(pushed_pass):
    """Table 3-5 at φ = 18° puts the contact at x_f = 0.234 m on a 0.203 m
    finger; the straight finger misses the object there: no contact."""
    assert THESIS_PASS[18][0][0] > UNIFORM.length
    assert not pushed_pass[18.0].contact


def test_fem_peak_is_matched_by_automatic_friction():
    """Table 3-6 (FEM) peaks at 31.8 N; the thesis's analytic pass at ~23 N.
    With friction opposing the actual sliding, ours peaks within 5% of the FEM;
    with the thesis's fixed convention it peaks within 10% of its analytic."""
    auto = thesis_pass("auto", 1.0)
    push = thesis_pass("push", 1.0)
    assert max(s.force for s in auto.values()) == pytest.approx(31.8, rel=0.05)
    assert max(s.force for s in push.values()) == pytest.approx(23.4, rel=0.10)
    # where the FEM finds no contact, neither do we
    pose, ell = scene(pass_angle(-0.254), (-0.254, 0.184))
    assert RobustContact(UNIFORM, 0.6041).solve(pose, ell, "push").force == FEM_PASS[-0.254]


def test_pass_geometry_helpers_are_inverse():
    for phi in [180.0, 126.0, 18.0]:
        assert pass_angle(pass_position(phi)) == pytest.approx(phi)
