"""The planar contact solver on random valid poses: the
object clear of the drum, the straight finger entering it at about a quarter
of its length, µ = 0 and 0.4. Before the fix 7 of these 400 imposed-side
solves (4 of the 200 below) and one pose of a sequence came back "the
contact reached the finger's base ... the object presses on the drum",
although the object is at least 2 cm from the base: the solver's way in
from first touch had carried the object over the base.
``python -m benchmarks.contact_poses`` runs 1000 poses."""

import numpy as np
import pytest

from design.physics.contact import SIDES
from design.physics.ellipse import Ellipse
from design.solvers.contact import RobustContact
from design.solvers.contact.robust import BASE_FRACTION, BASE_REACHED
from tests import prefetch
from tests.contact_reference import reference
from tests.problems import entering_poses, thesis_finger

POSES = entering_poses(seed=12, count=200)
FINGER = thesis_finger()
#: the reference's own error on the contact point (m) and, relative, on the
#: force: solve_bvp at a relative residual of 1e-8 agrees with the solver on
#: a 4x finer mesh (40 intervals) to 8e-13 m and 2e-10 (the first 60 poses
#: below), and to 4e-12 m on the finger bent 140° by 396 N; 1e-7 leaves a
#: wide margin
REFERENCE_ERROR = 1e-7
#: the prefetch key of :func:`imposed_side_references`
REFERENCES = "tests/test_contact_poses.py: imposed-side references"


def base_distance(pose, ell) -> float:
    """Least distance from the finger's base to the object (m)."""
    e = pose.view(ell)
    return float(np.min(np.hypot(*e.point(np.linspace(0.0, 2 * np.pi, 3601)))))


def imposed_side(i: int) -> tuple[float, str]:
    """Pose i's friction and imposed side: µ alternating, push and pull in pairs."""
    return (0.0, 0.4)[i % 2], ("push", "pull")[(i // 2) % 2]


def imposed_side_references() -> list:
    """The independent reference of every pose on its imposed side (None
    where that side has no equilibrium): 13 s, computed ahead in the
    session's prefetch worker (tests/prefetch.py) when it runs."""
    return [reference(FINGER, pose.view(ell), imposed_side(i)[0], SIDES[imposed_side(i)[1]])
            for i, (pose, ell) in enumerate(POSES)]


@pytest.fixture(scope="module")
def solvers():
    return {mu: (RobustContact(FINGER, mu), RobustContact(FINGER, mu, intervals=20))
            for mu in (0.0, 0.4)}


def test_imposed_side_matches_the_least_energy_reference(solvers):
    """Every pose, with the side imposed (push and pull in turn), is the
    equilibrium the independent reference finds on that side: the least-
    energy finger refined by a boundary-value solve (tests/contact_reference.py).

    Tolerance on the contact point and the force: the reference's error plus
    twice the solver's own mesh error, measured as the change from 10 to 20
    collocation intervals (degree 4 converges fast enough that this bounds
    the error of the coarser mesh; it is largest, ~1e-6 m, for fingers bent
    through 140° around the object's end). Distinct equilibria of one pose lie
    centimetres apart. Where the reference finds no equilibrium on the
    imposed side, the solver must say so and name the side that has one."""
    references = prefetch.result(REFERENCES, imposed_side_references)
    for i, (pose, ell) in enumerate(POSES):
        mu, sliding = imposed_side(i)
        coarse, fine = solvers[mu]
        sol = coarse.solve(pose, ell, sliding)
        ref = references[i]
        where = f"pose {i} (µ = {mu}, {sliding}): {sol.message}"
        if ref is None:
            assert not sol.converged and "other side" in sol.message, where
            continue
        assert sol.converged and sol.contact and sol.side == sliding, where
        assert sol.tip_contact == ref.tip_contact, where
        finer = fine.solve(pose, ell, sliding)
        mesh_error = np.hypot(*np.subtract(sol.point, finer.point))
        assert np.hypot(*np.subtract(sol.point, ref.point)) <= \
            REFERENCE_ERROR + 2 * mesh_error, where
        force_error = REFERENCE_ERROR * ref.force + 2 * abs(sol.force - finer.force)
        assert abs(sol.force - ref.force) <= force_error, where


@pytest.mark.parametrize("mu", [0.0, 0.4])
def test_automatic_side_solves_every_pose(mu, solvers):
    """With the side left to the solver every pose has an equilibrium, alone
    and as a sequence of unrelated poses (each continued from the last one,
    or found afresh when that fails)."""
    coarse, _ = solvers[mu]
    alone = [coarse.solve(pose, ell, "auto") for pose, ell in POSES]
    chained = coarse.solve_pass(*map(list, zip(*POSES)), "auto")
    for i, (a, c) in enumerate(zip(alone, chained)):
        for sol in (a, c):
            assert sol.converged and sol.contact and sol.penetration == 0.0, \
                f"pose {i}: {sol.message}"


def test_base_reached_only_where_the_object_is_at_the_base():
    """The object about 1 mm from the finger's base, the straight finger
    through it: the contact runs into the base whichever way the solver comes in,
    and that is what it says. On the random poses (the object at least
    2 cm from the base) it never says so."""
    finger, pose = FINGER, POSES[0][0]
    e_f = Ellipse(0.05, 0.03, (0.0505, 0.001), 0.0)     # nearest point (0.5, 1) mm
    c = pose.to_world(*e_f.center)[:, 0]
    ell = Ellipse(e_f.a, e_f.b, (float(c[0]), float(c[1])), pose.angle)
    assert base_distance(pose, ell) < BASE_FRACTION * finger.length
    for sliding in ("push", "pull", "auto"):
        sol = RobustContact(finger, 0.4).solve(pose, ell, sliding)
        assert not sol.converged and sol.message == BASE_REACHED, sol.message
    assert min(base_distance(p, e) for p, e in POSES) > BASE_FRACTION * finger.length


def test_a_sequence_never_continues_into_the_object():
    """Poses 565-567 of benchmarks/contact_poses.py's seed in sequence: the
    last continued from the one before passes 12.5 µm into the object away
    from the contact (a second contact, outside the model); the solver
    drops it for the equilibrium found afresh, the pose's own when solved
    alone."""
    poses = entering_poses(seed=2012, count=568)[565:]
    solver = RobustContact(FINGER, 0.0)
    last = solver.solve_pass(*map(list, zip(*poses)), "auto")[-1]
    alone = solver.solve(*poses[-1], "auto")
    assert last.converged and last.penetration == 0.0, last.message
    assert last.force == pytest.approx(alone.force, rel=1e-9)
    np.testing.assert_allclose(last.point, alone.point, atol=1e-12)
