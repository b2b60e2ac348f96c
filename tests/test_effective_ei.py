"""Effective EI (MODEL.md §2.3, thesis §2.4.3 and Table 5-2)."""

import numpy as np
import pytest

from design.physics.beam import PointLoad
from design.solvers.effective_ei import THESIS_CALIBRATION, effective_ei, effective_ei_table
from tests.closed_forms import EFFECTIVE_EI_REL, effective_ei as independent
from tests.problems import HARD_E, table_2_3, thesis_finger, uniform_finger

#: the thesis's printed effective EIs (N m^2) and the report's tolerance for
#: them, half a unit in the printed digit (design/reproduce/beam_rows.py)
TABLE_2_3_EI, TABLE_2_3_TOL = 0.081, 5e-4
TABLE_5_2_SOFT, TABLE_5_2_TOL = 0.1108, 5e-5


def test_table_2_3_effective_ei():
    """Table 2-3's load: slope matching (0.0541 N m^2), x1.48 (0.0800) and
    position matching (0.0784) are the independent closed-form values. The
    thesis prints 0.081: ours is 9.7e-4 below, outside half its printed
    digit (the report's tolerance), and the report's row says so; the
    thesis prints neither its ψ0 nor its slope match, so the cause is open."""
    finger, load = table_2_3()
    e = effective_ei(finger, load)
    slope, position = independent(finger.stiffness.ei, load.force, load.at)
    assert e.slope_matched == pytest.approx(slope, rel=EFFECTIVE_EI_REL)
    assert e.thesis == pytest.approx(THESIS_CALIBRATION * e.slope_matched)
    assert e.position_matched == pytest.approx(position, rel=EFFECTIVE_EI_REL)
    assert abs(e.thesis - TABLE_2_3_EI) > TABLE_2_3_TOL
    # the position-matched stand-in is the closest uniform beam by construction,
    # and the raw slope match is far off (why the thesis needed its factor)
    assert e.distance_position_matched <= e.distance_thesis <= e.distance_slope_matched
    assert e.distance_slope_matched > 5 * e.distance_position_matched


def test_uniform_finger_is_its_own_effective_ei():
    finger = uniform_finger(0.08)
    e = effective_ei(finger, PointLoad(15.0, 1.2, 0.12))
    assert e.slope_matched == pytest.approx(0.08, rel=1e-9)
    assert e.position_matched == pytest.approx(0.08, rel=1e-6)
    assert e.distance_position_matched < 1e-9


def test_table_5_2_trend_soft_and_hard():
    """Table 5-2: effective EI falls as the contact moves out (soft: 0.1108 at
    50.8 mm ... 0.0506 at 127 mm), and the hard finger is 9.07/4.8 = 1.89x the
    soft one. Ours (position match at 15 N transverse) is the independent
    closed-form value at every position. The thesis averaged over 'a range of
    forces and angles' it does not list: at 50.8 mm its 0.1108 is 1.5e-4
    above ours (0.11065), outside half its printed digit, as the report says."""
    positions = [0.0508, 0.06604, 0.08128, 0.09653, 0.11176, 0.127]
    soft = effective_ei_table(thesis_finger(), positions, 15.0, np.pi / 2)
    hard = effective_ei_table(thesis_finger(HARD_E), positions, 15.0 * HARD_E / 4.8e6, np.pi / 2)
    ei_soft = np.array([r.position_matched for r in soft])
    assert np.all(np.diff(ei_soft) < 0)
    for r in soft:
        _, position = independent(thesis_finger().stiffness.ei, r.load.force, r.load.at)
        assert r.position_matched == pytest.approx(position, rel=EFFECTIVE_EI_REL)
    assert abs(ei_soft[0] - TABLE_5_2_SOFT) > TABLE_5_2_TOL
    # scaling E and F together leaves the shape unchanged: EI scales with E exactly
    ratio = np.array([r.position_matched for r in hard]) / ei_soft
    np.testing.assert_allclose(ratio, HARD_E / 4.8e6, rtol=1e-6)
