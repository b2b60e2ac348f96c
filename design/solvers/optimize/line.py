"""The line's rate as a design goal: birds per minute under eq. 5.3-5.4.

A drum with n finger sets turning at ω (rad/s) meets n ω / 2π birds a second
(each set grasps one bird per turn), so the line runs

    rate = 60 n ω / 2π   birds per minute

and the belt, by eq. 5.3, at v = n Δx ω / 2π with the birds Δx apart. The
thesis's grasper (three sets at 20 rpm) runs 60 birds/min; the kill line
it feeds runs 180 (§1).

Eq. 5.4 bounds the sets by the included angle φ_a of one set, n ≤ 2π/φ_a;
φ_a is read here as the angle the set's fingers span on the drum (the
largest layout angle less the smallest: 45° for Table 5-1, n ≤ 8).

``objective: throughput`` maximises the rate with every bird of the
population held off the belt at least ``min_hold``, under the cap and its
fingers' fold forces, and carried on without a jam. Its comparison of two
simulated designs (:func:`faster`) ranks, in turn: keeping the cap, the
fold forces and no jam (else the nearer to it, as the hold objective
does), reaching ``min_hold`` (else the longer hold), the higher rate, and
the longer hold by more than the search's band.
"""

from __future__ import annotations

import math


from design.physics.grasper import Grasper
from design.solvers.grasp.validity import finger_limits
from design.solvers.optimize.trust_region import Scored, better, unmeasured_jams

#: the thesis's grasper and the kill line it feeds (birds per minute)
THESIS_RATE, KILL_LINE_RATE = 60.0, 180.0


def rate(sets: int, drum_speed: float) -> float:
    """Birds per minute of a drum with ``sets`` finger sets at ``drum_speed`` (rad/s)."""
    return 60.0 * sets * drum_speed / (2 * math.pi)


def rate_of(scored: Scored) -> float:
    """The rate (birds/min) of a simulated design (every bird's line is the same)."""
    setup = scored.members[0].run.setup
    return rate(setup.grasper.sets, setup.drum_speed)


def included_angle(grasper: Grasper) -> float:
    """φ_a (rad): the angle one set's fingers span on the drum."""
    angles = [gf.mount.angle - gf.phase for gf in grasper.fingers]
    return max(angles) - min(angles)


def max_sets(grasper: Grasper) -> int:
    """The most finger sets eq. 5.4 allows, n ≤ 2π/φ_a (at least one)."""
    phi = included_angle(grasper)
    return max(1, math.floor(2 * math.pi / phi + 1e-9)) if phi > 0 else 12


def faster(a: Scored, b: Scored, caps, min_hold: float, band: float) -> bool:
    """Is a better than b for ``objective: throughput`` (module docstring)?"""
    standing_a, standing_b = _standing(a, caps, min_hold), _standing(b, caps, min_hold)
    if standing_a != standing_b:
        return standing_a > standing_b
    if standing_a == 0:                                 # both break a limit or jam
        return better(a, b, caps, tolerance=0.0, band=band)
    if standing_a == 2:
        rate_a, rate_b = rate_of(a), rate_of(b)
        if abs(rate_a - rate_b) > 1e-9 * rate_b:
            return rate_a > rate_b
    return a.hold > b.hold + band


def _standing(scored: Scored, caps, min_hold: float) -> int:
    """0: a limit broken or a bird jammed; 1: within them, some bird held
    less than ``min_hold``; 2: every rule kept."""
    if not scored.within(caps):
        return 0
    return 2 if scored.holds.min() >= min_hold else 1


def broken(scored: Scored, caps, min_hold: float) -> list[str]:
    """The rules a simulated design breaks, bird by bird: a run that ended
    early, a jam, a finger over the cap or its fold force, a hold shorter
    than ``min_hold``."""
    out = []
    for member, (evaluated, cap) in zip(scored.population.members, scored.with_caps(caps)):
        s, setup = evaluated.run.summary, evaluated.run.setup
        if not s["ok"]:
            out.append(f"{member.name}: its simulation ended early ({s['message']})")
            continue
        out += [f"{member.name}: {reason}" for reason in unmeasured_jams(s)]
        for gf, limit in zip(setup.grasper.fingers, finger_limits(setup, cap)):
            force = s["max_force_per_finger_N"][gf.name]
            if force > limit:
                rule = "the cap" if limit == cap else "its fold force"
                out.append(f"{member.name}: finger {gf.name} presses {force:.2f} N, over "
                           f"{rule} {limit:.2f} N")
        if evaluated.hold < min_hold:
            out.append(f"{member.name}: held {evaluated.hold:.4f} s, under the "
                       f"{min_hold:g} s asked")
    return out
