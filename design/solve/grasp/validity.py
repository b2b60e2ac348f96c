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
* A finger that passes below the conveyor's surface under the bird is
  reported: the thesis's birds and football sit on pallets at least as wide
  as the bird (§A, Fig 1-1), so a finger point below Z = 0 within the bird's
  footprint (|Y| < λ, |X - X_bird| < η) would cut through the pallet.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np
from scipy.optimize import brentq

from design.physics.beam import Finger, PointLoad
from design.solve.beam import solve_beam

#: tip slope (rad) that defines a finger's fold force
FOLD_SLOPE = np.radians(80.0)
#: largest out-of-plane share of the contact normal the planar model may see
PLANAR_LIMIT = 0.3


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


def contact_validity(run, peaks: np.ndarray, peak_times: np.ndarray) -> dict:
    """Per finger: the largest out-of-plane shares of contact normal and sweep,
    the fold force and whether its largest force (``peaks``, N, at
    ``peak_times``, s: the summary's, located between records where they
    are) passed it; fingers through the conveyor; and whether the planar
    model stayed inside its limit."""
    recs = run.trajectory.records
    setup = run.setup
    b = setup.bird
    drum = setup.grasper.drum(setup.drum_speed)
    per_finger, beyond, through = {}, [], []
    for i, gf in enumerate(setup.grasper.fingers):
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
        for r, f in touching:
            pts = _finger_points(drum, gf, r.t, f)
            under = (pts[2] < 0) & (np.abs(pts[1]) < b.lam) & (np.abs(pts[0] - r.y[0]) < b.eta)
            if np.any(under):
                through.append({"finger": gf.name, "time_s": r.t,
                                "depth_m": float(-pts[2][under].min())})
                break
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


def validity_problems(validity: dict) -> list[str]:
    """A run's reasons to distrust its model, in words (empty: none)."""
    out = []
    if not validity["planar_model_valid"]:
        out.append(f"contact normals reach {validity['normal_out_of_plane_max']:.2f} out of the "
                   f"fingers' planes (planar model limit {PLANAR_LIMIT})")
    out += [f"finger {b['finger']} pressed {b['force_N']:.1f} N, past its fold force "
            f"{b['fold_force_N']:.1f} N, at {b['time_s']:.3f} s"
            for b in validity["forces_beyond_fold"]]
    out += [f"finger {b['finger']} passed {1e3 * b['depth_m']:.1f} mm through the belt under "
            f"the bird at {b['time_s']:.3f} s" for b in validity["fingers_through_conveyor"]]
    held = validity.get("held_at_start", [])
    if held:
        out.append("the bird starts held off the belt by finger(s) " + ", ".join(
            f"{h['finger']} ({h['force_N']:.1f} N)" for h in held) + " at t = 0, placed inside "
            "their reach: the first hold window begins with the run, not with a grasp")
    return out
