"""The spatial finger model inside a grasp run (docs/MODEL.md, "spatial")."""

import numpy as np

from design.reproduce.grasp import MEAN_START, mean_bird_setup
from design.solvers.grasp.fingers import FingerForces


def fingers_of(setup) -> FingerForces:
    return FingerForces(setup.grasper, setup.bird, setup.drum_speed, setup.finger_friction,
                        model="spatial", intervals=6)


def test_the_loads_are_a_function_of_the_state():
    """Loads at an accepted instant, continued from the state committed one
    step earlier, equal the loads there continued from the state committed
    at that instant itself (1e-9 relative: the Newton tolerance). Table 5-3's
    mean bird, soft lower fingers, at Table 5-3's X0 = -0.075 m with the
    fingers at Table 5-1's angles: finger 4a slides along it (µ = 0.4). The friction is solved at the contact point itself; taken from
    the previous solution's point, it made the loads jump at every accepted
    step (0.03 m/s² in 0.05 m/s², measured on the football), which forced
    1e-4 s steps."""
    setup = mean_bird_setup("soft")
    b = setup.bird
    y0 = np.array([MEAN_START, b.gamma + 0.002, 0.0, setup.conveyor.speed, 0.0, 0.0])
    y1 = y0 + 0.004 * np.concatenate([y0[3:], [0.0, 0.0, 0.0]])
    stepping = fingers_of(setup)
    stepping.evaluate(0.0, y0, commit=True)
    committed, states = stepping.evaluate(0.004, y1, commit=True)
    again = fingers_of(setup)
    again.states = list(stepping.states)
    trial, _ = again.evaluate(0.004, y1)
    force = next(s for s in states if s.magnitude > 0)
    assert force.magnitude > 5.0 and abs(force.solution.extras["friction"] @ force.solution.normal) < 1e-9
    loads = np.array([committed.qx, committed.qz, committed.ty])
    np.testing.assert_allclose([trial.qx, trial.qz, trial.ty], loads,
                               atol=1e-9 * np.abs(loads).max())
