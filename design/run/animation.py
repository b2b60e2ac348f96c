"""What a run's result keeps for its animation: the bird's state at evenly
spaced frame times, and each animated run's scene.

A run is animated at t = 0, step, 2 step, ... (:func:`frame_step`: the
finest of FRAME_STEPS that gives at most MAX_FRAMES frames, so a long run
is drawn at a coarser step). Its recorded instants fall where the
integrator's steps fell, so the state at each frame (X, Z, θ and their
rates), the belt's normal force N and the belt's travel are interpolated
linearly between them. The fingers are not kept: the report and ``design
animate`` solve them again at these states (design/report/animation.py).
"""

from __future__ import annotations

import numpy as np

#: the frame steps (s) a run is animated at
FRAME_STEPS = (0.01, 0.02, 0.025, 0.04, 0.05, 0.1, 0.2, 0.5)
#: the most frames of a run: each costs a report 4-8 kB per run drawn
MAX_FRAMES = 81
#: the bird's state columns kept at every frame (timeseries.csv's names)
STATE = ("X_m", "Z_m", "theta_rad", "Xdot_m_s", "Zdot_m_s", "thetadot_rad_s")


def frame_step(duration: float) -> float:
    """The animation's time step (s) for a run of ``duration`` (s)."""
    return next((dt for dt in FRAME_STEPS if duration / dt + 1 <= MAX_FRAMES + 1e-9),
                FRAME_STEPS[-1])


def frame_states(columns: dict[str, list], step: float) -> dict[str, list[float]]:
    """The run's state at t = 0, step, 2 step, ... up to its last recorded
    instant, interpolated linearly from ``columns`` (timeseries.csv's t_s,
    STATE, N_N and belt_speed_m_s), with the belt's travel belt_travel_m (m,
    the trapezoidal integral of its speed)."""
    t = np.asarray(columns["t_s"], float)
    times = step * np.arange(int(np.floor(t[-1] / step + 1e-9)) + 1)
    speed = np.asarray(columns["belt_speed_m_s"], float)
    travel = np.concatenate([[0.0], np.cumsum(np.diff(t) * (speed[1:] + speed[:-1]) / 2)])
    out = {"t_s": times.tolist()}
    for name in (*STATE, "N_N"):
        out[name] = np.interp(times, t, np.asarray(columns[name], float)).tolist()
    out["belt_travel_m"] = np.interp(times, t, travel).tolist()
    return out


def animation_record(runs: dict[str, tuple[dict, list[dict]]], cap: float | None) -> dict:
    """A result's ``animation``: for each run (label -> (its scene, as a
    scene file's content, and its timeseries.csv rows)) the scene, how many
    instants it recorded and its states at the frame times; ``cap`` (N) the
    bruise cap the forces are coloured against (None: no cap)."""
    step = frame_step(max(rows[-1]["t_s"] for _, rows in runs.values()))
    out = {"frame_step_s": step, "cap_N": cap, "runs": {}}
    for label, (scene, rows) in runs.items():
        columns = {k: [r[k] for r in rows] for k in ("t_s", *STATE, "N_N", "belt_speed_m_s")}
        out["runs"][label] = {"scene": scene, "recorded_instants": len(rows),
                              "states": frame_states(columns, step)}
    return out
