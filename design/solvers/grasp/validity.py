"""What a grasp run's contacts say about the model's validity and the physics.

* The fold force of a finger: the transverse force at its tip that turns the
  tip's slope to FOLD_SLOPE. Past it the finger is folded over, its tip
  pointing along the push; a contact force well above it means the bird is
  jammed against the finger near its base or the drum, which the finger
  models do not represent. Forces above it are listed, not hidden.
* The planar (thesis) model keeps only the in-plane part of a contact. It
  stands for the physics only while the bird's surface normal at the
  contact stays near the finger's plane: |n·z_f| ≤ PLANAR_LIMIT, a normal
  leaning at most 17.5° out of it (sin 17.5° = 0.3: the discarded part of
  the push is then under 5% of it and the in-plane force points within
  17.5° of the true one).
* A run that starts with the bird already held off the belt (N = 0 at
  t = 0, a finger pressing on it) begins inside a grasp that no finger
  swept into: its first hold window is an artefact of the start, and the
  run says so.
* A finger that passes below the belt's surface where the belt is (design/
  physics/belt.py: a solid belt by default) by more than BELT_TOLERANCE is
  reported: the fingers rest on the belt with their tips, and a finger
  lying on it along its length, or one solved without the belt, would cut
  through it.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np
from scipy.optimize import brentq

from design.physics.beam import Finger, PointLoad
from design.solvers.beam import solve_beam

#: tip slope (rad) that defines a finger's fold force
FOLD_SLOPE = np.radians(80.0)
#: largest out-of-plane share of the contact normal the planar model may see
PLANAR_LIMIT = 0.3
#: a finger point this far (m) below the belt's surface is reported
BELT_TOLERANCE = 1e-4


@lru_cache(maxsize=64)
def fold_force(finger: Finger) -> float:
    """Transverse tip force (N) at which the finger's tip slope reaches
    FOLD_SLOPE (planar elastica, collocation)."""
    def slope(force: float) -> float:
        sol = solve_beam(finger, [PointLoad(force, np.pi / 2, finger.length)])[0]
        return sol.tip[2] - FOLD_SLOPE

    f0 = float(finger.stiffness.ei(0.0)) / finger.length ** 2
    hi = f0
    while slope(hi) < 0:
        hi *= 2
    return float(brentq(slope, hi / 2 if slope(hi / 2) < 0 else 0.0, hi, xtol=1e-3 * hi))


def finger_limits(setup, cap: float) -> np.ndarray:
    """Each finger's force limit (N): the cap or its fold force, the lower."""
    return np.array([min(cap, fold_force(gf.finger)) for gf in setup.grasper.fingers])


def contact_validity(run, peaks: np.ndarray, peak_times: np.ndarray) -> dict:
    """Per finger: the largest out-of-plane shares of contact normal and sweep,
    the fold force and whether its largest force (``peaks``, N, at
    ``peak_times``, s: the summary's, located between records where they
    are) passed it; fingers through the conveyor; and whether the planar
    model stayed inside its limit."""
    recs = run.trajectory.records
    setup = run.setup
    drum = setup.grasper.drum(setup.drum_speed)
    per_finger, beyond, through = {}, [], []
    for i, gf in enumerate(setup.grasper.fingers):
        below = _below_belt(setup, drum, gf, [(r.t, r.fingers[i]) for r in recs])
        if below is not None:
            through.append({"finger": gf.name, "time_s": below[0], "depth_m": below[1]})
        touching = [(r, r.fingers[i]) for r in recs if r.fingers[i].magnitude > 0]
        if not touching:
            continue
        bound = fold_force(gf.finger)
        peak = float(peaks[i])
        per_finger[gf.name] = {
            "normal_out_of_plane_max": max(f.normal_out_of_plane for _, f in touching),
            "sweep_out_of_plane_max": max(f.sweep_out_of_plane for _, f in touching),
            "fold_force_N": bound, "max_force_N": peak}
        if peak > bound:
            beyond.append({"finger": gf.name, "time_s": float(peak_times[i]), "force_N": peak,
                           "fold_force_N": bound})
    worst = max((v["normal_out_of_plane_max"] for v in per_finger.values()), default=0.0)
    first = recs[0]
    held = [(gf.name, f.magnitude) for gf, f in zip(setup.grasper.fingers, first.fingers)
            if f.magnitude > 0] if first.mode == "air" else []
    return {"fingers": per_finger, "forces_beyond_fold": beyond,
            "held_at_start": [{"finger": n, "force_N": f} for n, f in held],
            "fingers_through_conveyor": through,
            "normal_out_of_plane_max": worst,
            "planar_model_valid": setup.finger_model == "spatial" or worst <= PLANAR_LIMIT}


def _finger_points(drum, gf, t: float, state) -> np.ndarray:
    base, R = drum.frame(gf.mount, t)
    pts = getattr(state.solution, "shape_points", None)
    if pts is None:
        pts = np.vstack([np.linspace(0.0, gf.finger.length, 12), np.zeros((2, 12))])
    return base[:, None] + R @ pts


def _below_belt(setup, drum, gf, states) -> tuple[float, float] | None:
    """(time s, depth m) of the finger's deepest point below the belt where
    the belt is, among its solved ``states`` [(t, FingerState)], if deeper
    than BELT_TOLERANCE."""
    deepest = None
    for t, state in states:
        if state.solution is None:
            continue
        pts = _finger_points(drum, gf, t, state)
        on = np.array([setup.belt.touches(gf.design_name, y) for y in pts[1]])
        if not np.any(on):
            continue
        depth = float(-pts[2][on].min())
        if depth > BELT_TOLERANCE and (deepest is None or depth > deepest[1]):
            deepest = (float(t), depth)
    return deepest


def belt_contacts(run) -> dict:
    """Per finger that pressed on the belt: its largest normal force on it (N)
    and when (s), and the first and last instants it touched (s)."""
    recs = run.trajectory.records
    out = {}
    for i, gf in enumerate(run.setup.grasper.fingers):
        on = [(r.t, r.fingers[i].belt_force) for r in recs if r.fingers[i].belt_force > 0.0]
        if on:
            t_max, f_max = max(on, key=lambda x: x[1])
            out[gf.name] = {"max_force_N": f_max, "time_s": t_max, "first_s": on[0][0],
                            "last_s": on[-1][0]}
    return out


def validity_problems(validity: dict) -> list[str]:
    """A run's reasons to distrust its model, in words (empty: none). A finger
    past its fold force is a jam (design/solvers/grasp/simulation.py's
    :func:`jam`), named there."""
    out = []
    if not validity["planar_model_valid"]:
        out.append(f"contact normals reach {validity['normal_out_of_plane_max']:.2f} out of the "
                   f"fingers' planes (planar model limit {PLANAR_LIMIT})")
    out += [f"finger {b['finger']} passed {1e3 * b['depth_m']:.1f} mm through the belt at "
            f"{b['time_s']:.3f} s" for b in validity["fingers_through_conveyor"]]
    held = validity.get("held_at_start", [])
    if held:
        out.append("the bird starts held off the belt by finger(s) " + ", ".join(
            f"{h['finger']} ({h['force_N']:.1f} N)" for h in held) + " at t = 0, placed inside "
            "their reach: the first hold window begins with the run, not with a grasp")
    return out
