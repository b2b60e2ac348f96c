"""What a grasp run says about its own validity (design/solvers/grasp/validity.py)."""

from dataclasses import replace

from design.reproduce.grasp import mean_bird_setup
from design.solvers.grasp.integrate import IntegratorSettings
from design.solvers.grasp.simulation import simulate_grasp
from design.solvers.grasp.validity import validity_problems


def short(setup, duration=0.01):
    return simulate_grasp(replace(setup, duration=duration), IntegratorSettings())


def test_a_bird_placed_inside_a_fingers_reach_is_flagged_as_held_from_the_start():
    """Table 5-3's start as printed puts the mean bird on finger 4a at t = 0,
    off the belt (N = 0) before any finger swept into it: the run says its
    first hold window is an artefact of the start. The arriving bird (one
    set period upstream) rides the belt at t = 0: no such flag."""
    placed = short(mean_bird_setup("hard", "planar", arriving=False))
    held = placed.summary["validity"]["held_at_start"]
    assert placed.trajectory.records[0].normal == 0.0
    assert [h["finger"] for h in held] == ["4a"] and held[0]["force_N"] > 5.0
    assert any("starts held off the belt by finger(s) 4a" in p
               for p in validity_problems(placed.summary["validity"]))
    arriving = short(mean_bird_setup("hard", "planar"))
    assert arriving.trajectory.records[0].normal > 0.0
    assert arriving.summary["validity"]["held_at_start"] == []
