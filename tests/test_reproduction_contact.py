"""The thesis's chapter III numbers, reproduced where they are unambiguous
(``design reproduce``'s report.html has the full tables).

Our forces and contact points are checked against an independent reference
(tests/contact_reference.py: a least-energy finger refined by solve_bvp,
sharing no code with the contact solver); the thesis's printed numbers are
then compared at the report's own tolerances (design/reproduce/contact_rows.py:
contact points 1.5 mm, forces 2 %), and where they fall outside, the test
says so instead of widening the tolerance."""

import numpy as np
import pytest

from design.physics.contact import SIDES, Motion
from design.physics.ellipse import Ellipse
from design.reproduce.contact import (CASES, FEM_PASS, OMEGA, SPEED, THESIS_CASES, THESIS_PASS,
                                      UNIFORM, pass_angle, pass_position, scene, table_3_1,
                                      thesis_pass)
from design.reproduce.contact_rows import FORCE_REL, POINT_TOL
from design.solvers.contact import RobustContact
from tests.contact_reference import reference

#: the reference's own error on the contact point (m) and, relative, on the
#: force (solve_bvp at a relative residual of 1e-8; see tests/test_contact_poses.py)
REFERENCE_ERROR = 1e-7


def assert_matches_reference(sol, finger, pose, ell, friction, sliding=None):
    """``sol`` is the reference's equilibrium on its side and with its
    friction ratio, to the reference's error plus twice our own mesh error
    (the change from 10 to 20 collocation intervals, as in test_contact_poses,
    solved the same way: the side imposed, or with ``sliding="auto"`` the
    pass's motion played back)."""
    ref = reference(finger, pose.view(ell), sol.extras["friction_ratio"], SIDES[sol.side])
    assert ref is not None and ref.tip_contact == sol.tip_contact
    motion = Motion(OMEGA, (SPEED, 0.0)) if sliding == "auto" else None
    finer = RobustContact(finger, friction, intervals=20).solve(pose, ell, sliding or sol.side,
                                                                motion)
    assert finer.side == sol.side and finer.extras["friction_ratio"] == sol.extras["friction_ratio"]
    mesh = np.hypot(*np.subtract(sol.point, finer.point))
    assert np.hypot(*np.subtract(sol.point, ref.point)) <= REFERENCE_ERROR + 2 * mesh
    force_error = REFERENCE_ERROR * ref.force + 2 * abs(sol.force - finer.force)
    assert abs(sol.force - ref.force) <= force_error
    return ref


def case_scene(case):
    center, phi, _ = CASES[case]
    pose, _ = scene(phi, center)
    return pose, Ellipse(0.0991, 0.0673, center)      # as table_3_1 solves it


@pytest.fixture(scope="module")
def cases():
    return table_3_1()


@pytest.fixture(scope="module")
def pushed_pass():
    return thesis_pass("push", 18.0)


def test_case_1_uniform_finger_matches_algorithm_one(cases):
    """Table 3-2, Case 1: contact (0.104, 0.045) m, ψ0 = 35.6°, α = 85.39°,
    printed to 3 digits and found to ERR = 0.5 mm; ours (EI = 0.08, the thesis's
    friction convention) within 1 mm and 0.5°, and equal to the independent
    reference. The thesis's 8.77 N is above ours by more than the report's 2 %
    (ours is 5.7 % lower, as in the pass: see the pass test)."""
    sol = cases[(1, "robust, uniform EI = 0.08")]
    point, alpha, force, psi, arc = THESIS_CASES[(1, "Algorithm I")]
    assert_matches_reference(sol, UNIFORM, *case_scene(1), 0.6)
    assert np.hypot(*np.subtract(sol.point, point)) < 1e-3
    assert np.degrees(sol.psi) == pytest.approx(psi, abs=0.5)
    assert np.degrees(sol.alpha) == pytest.approx(alpha, abs=0.5)
    assert sol.force < (1 - FORCE_REL) * force            # the report's row disagrees


def test_case_2_is_a_pull(cases):
    """Table 3-2, Case 2 (x = 0.0662 m, ψ0 = 74.13°, L = 111.4 mm, F = 18.72 N):
    matched by the pulled finger, which is the independent reference's
    equilibrium on that side, with y_f = -0.079 as Figure 3-7 shows (within
    the report's 1.5 mm; the table's +0.040 is a misprint). The thesis's
    force is above ours by more than the report's 2 % (ours is 2.6 % lower)."""
    sol = cases[(2, "robust, uniform EI = 0.08")]
    point, _, force, psi, arc = THESIS_CASES[(2, "Algorithm I")]
    assert sol.side == "pull"
    assert_matches_reference(sol, UNIFORM, *case_scene(2), 0.6)
    assert sol.point[0] == pytest.approx(point[0], abs=5e-4)
    assert sol.point[1] == pytest.approx(-0.079, abs=POINT_TOL)
    assert abs(np.degrees(sol.psi)) == pytest.approx(psi, abs=0.2)
    assert sol.arc_length == pytest.approx(arc, abs=5e-4)
    assert sol.force < (1 - FORCE_REL) * force            # the report's row disagrees


def test_effective_ei_stand_in_gets_the_force_not_the_contact_point(cases):
    """Against a rigid object a uniform finger's contact geometry does not depend
    on EI at all, so the effective-EI stand-in (position-matched to the soft
    finger's contact load) touches where the EI = 0.08 finger does, more than
    10 mm from the non-uniform finger's contact (measured 16 and 26 mm); only
    its force comes close (≤ 15 %; measured 9 % and 11 % low)."""
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
    """Table 3-5 at every listed φ but 18°: ours is the independent
    reference's equilibrium; the contact points lie within the report's
    1.5 mm of the thesis's (its 3 digits and 0.5 mm tolerance). Its forces
    are all higher than ours by more than the report's 2 %, and by one common
    factor to within that 2 % (measured: 1.054-1.095), as if its EI were
    about 7 % above Table 3-4's 0.08: a uniform finger's contact geometry
    does not depend on EI, and its force is proportional to it."""
    ratios = []
    for phi, (point, psi, force, _) in THESIS_PASS.items():
        sol = pushed_pass[float(phi)]
        if phi == 18:
            continue
        assert sol.contact and sol.converged
        assert_matches_reference(sol, UNIFORM, *scene(float(phi), (pass_position(phi), 0.184)),
                                 0.6041)
        assert np.hypot(*np.subtract(sol.point, point)) < POINT_TOL
        ratios.append(force / sol.force)
    assert min(ratios) > 1 / (1 - FORCE_REL)              # every force row disagrees
    assert max(ratios) / min(ratios) <= (1 + FORCE_REL) / (1 - FORCE_REL)


def test_pass_end_thesis_contact_lies_beyond_the_finger(pushed_pass):
    """Table 3-5 at φ = 18° puts the contact at x_f = 0.234 m on a 0.203 m
    finger; the straight finger misses the object there: no contact."""
    assert THESIS_PASS[18][0][0] > UNIFORM.length
    assert not pushed_pass[18.0].contact


def test_fem_peak_is_matched_by_automatic_friction():
    """Table 3-6 (FEM) peaks at 31.797 N; the thesis's analytic pass at
    23.365 N (Table 3-5's largest; Figure 3-17: about 23 N). With friction
    opposing the actual sliding, ours peaks within 5 % of the FEM (the
    report allows 10 % for this other model; measured -2.5 %); with the
    thesis's fixed convention within 10 % of its analytic peak (measured
    +4.9 %: its 6° table misses the peak between rows, and its forces are
    7 % above ours). Both peaks are the independent reference's equilibria."""
    auto = thesis_pass("auto", 1.0)
    push = thesis_pass("push", 1.0)
    analytic = max(v[2] for v in THESIS_PASS.values())
    for sliding, sols, thesis, rel in [("auto", auto, max(FEM_PASS.values()), 0.05),
                                       ("push", push, analytic, 0.10)]:
        phi, peak = max(sols.items(), key=lambda item: item[1].force)
        assert_matches_reference(peak, UNIFORM, *scene(phi, (pass_position(phi), 0.184)), 0.6041,
                                 sliding)
        assert peak.force == pytest.approx(thesis, rel=rel)
    # where the FEM finds no contact, neither do we
    pose, ell = scene(pass_angle(-0.254), (-0.254, 0.184))
    assert RobustContact(UNIFORM, 0.6041).solve(pose, ell, "push").force == FEM_PASS[-0.254]


def test_pass_geometry_helpers_are_inverse():
    for phi in [180.0, 126.0, 18.0]:
        assert pass_angle(pass_position(phi)) == pytest.approx(phi)
