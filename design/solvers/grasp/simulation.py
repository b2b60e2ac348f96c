"""One grasp simulation: set up, integrate, summarise (solver level, no I/O)."""

from __future__ import annotations

import time
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from design.physics.belt import Belt
from design.physics.bird import Bird, BirdDynamics, Conveyor, Legs
from design.physics.grasper import Grasper
from design.solvers.grasp.fingers import FingerForces, FingerState, reach_windows
from design.solvers.grasp.integrate import Grasp, IntegratorSettings, Trajectory, integrate
from design.solvers.grasp.peaks import merged_peaks
from design.solvers.grasp.validity import belt_contacts, contact_validity


#: the spatial rod's collocation intervals: 3 change hold and peak by under
#: 5e-6 (relative) against 10, at 0.45x the time of the default 6
#: (benchmarks/spatial_mesh.py); the planar finger keeps the default
SPATIAL_NODES = 3


@dataclass(frozen=True)
class GraspSetup:
    """The physical system and its start (SI)."""

    grasper: Grasper
    bird: Bird
    conveyor: Conveyor
    drum_speed: float
    start_x: float
    finger_friction: float
    conveyor_friction: float
    legs: Legs
    duration: float
    #: the fingers' contact model: ``spatial`` (rod) or ``planar`` (thesis, default)
    finger_model: str = "planar"
    #: where the fingers can meet the belt (default: a solid belt)
    belt: Belt = Belt()
    #: the finger-belt friction coefficient (None: the conveyor's, ``conveyor_friction``)
    belt_friction: float | None = None

    @property
    def finger_belt_friction(self) -> float:
        return self.conveyor_friction if self.belt_friction is None else self.belt_friction


@dataclass
class GraspRun:
    setup: GraspSetup
    trajectory: Trajectory
    windows: list | None
    contact_solves: int
    skipped: int
    setup_time: float
    #: the instants the run looked for fingers reaching the bird, (t, X, Z,
    #: pitch) (n, 4), and the fingers it found reaching (FingerForces.probes)
    probes: np.ndarray | None = None
    reached: frozenset = frozenset()

    @cached_property
    def summary(self) -> dict:
        """:func:`summarise`, computed once (0.09 s for a 0.6 s mean-bird run;
        the design loop reads it dozens of times per simulation)."""
        return summarise(self)

    def peak(self) -> tuple[float, np.ndarray, FingerState]:
        """The summary's peak finger force: (time s, the bird's state, the
        finger's contact), at a record or located between records."""
        s = self.summary
        j = [gf.name for gf in self.setup.grasper.fingers].index(s["max_finger_force_finger"])
        located = self.trajectory.peaks.get(j)
        if located is not None and located.t == s["max_finger_force_time_s"]:
            return located.t, located.y, located.state
        r = next(r for r in self.trajectory.records if r.t == s["max_finger_force_time_s"])
        return r.t, r.y, r.fingers[j]


def simulate_grasp(setup: GraspSetup, integrator: IntegratorSettings = IntegratorSettings(),
                   contact_nodes: int = 6, reach_filter: bool = True, progress=None,
                   watch=None) -> GraspRun:
    """Integrate the symmetric grasp from the bird sitting on the belt at
    start_x; ``watch`` (a trajectory -> the reason to end it, or "") may
    end the run early (design/solvers/grasp/cutoff.py)."""
    t0 = time.perf_counter()
    b, conv = setup.bird, setup.conveyor
    windows = setup_reach_windows(setup) if reach_filter else None
    fingers = FingerForces(setup.grasper, b, setup.drum_speed, setup.finger_friction, windows,
                           intervals=contact_nodes, model=setup.finger_model, belt=setup.belt,
                           belt_friction=setup.finger_belt_friction)
    dyn = BirdDynamics(b, setup.legs, setup.conveyor_friction)
    grasp = Grasp(dyn, conv, fingers)
    y0 = np.array([setup.start_x, b.gamma, 0.0, conv.speed, 0.0, 0.0])
    setup_time = time.perf_counter() - t0
    traj = integrate(grasp, y0, setup.duration, integrator, progress, watch)
    return GraspRun(setup, traj, windows, fingers.solves, fingers.skipped, setup_time,
                    np.array(fingers.probes, float).reshape(-1, 4), frozenset(fingers.reached))


def setup_reach_windows(setup: GraspSetup) -> list[list[tuple[float, float]]]:
    """Per finger, the time windows (s) in which it can touch the bird (see
    :func:`~design.solvers.grasp.fingers.reach_windows`): the belt carries the
    bird, its centre following X0 + v t; a decelerating belt gives a band
    covering both of its speeds."""
    b, conv = setup.bird, setup.conveyor

    def windows_at(speed: float):
        return reach_windows(setup.grasper, b, setup.drum_speed,
                             lambda t: (setup.start_x + speed * t, b.gamma), setup.duration)

    if not conv.changes:
        return windows_at(conv.speed)
    return [_union(w1, w2) for w1, w2 in zip(windows_at(conv.final_speed),
                                             windows_at(conv.speed))]


def _union(a, b):
    spans = sorted(a + b)
    out = []
    for lo, hi in spans:
        if out and lo <= out[-1][1]:
            out[-1] = (out[-1][0], max(out[-1][1], hi))
        else:
            out.append((lo, hi))
    return out


class HoldWindows:
    """The hold windows (N = 0) of a run's records taken in order: those
    ``closed`` ((start, end) s) and the ``start`` (s) of one still open (None:
    the belt supports the bird). A touch-down ends a window even when the
    bird bounces straight off: the belt's impulse carried it at that
    instant."""

    def __init__(self):
        self.closed: list[tuple[float, float]] = []
        self.start: float | None = None

    def add(self, record, impact: bool) -> None:
        """The next record; ``impact``: a touch-down at its instant."""
        if record.mode == "air" and self.start is not None and impact and record.t > self.start:
            self.closed.append((self.start, record.t))
            self.start = record.t
        elif record.mode == "air" and self.start is None:
            self.start = record.t
        elif record.mode != "air" and self.start is not None:
            self.closed.append((self.start, record.t))
            self.start = None


def hold_windows(run: GraspRun) -> list[tuple[float, float]]:
    """Intervals (s) in which the belt does not support the bird (N = 0)
    (:class:`HoldWindows`). The last window may run to the end of the run
    (the bird not yet put back)."""
    recs = run.trajectory.records
    impacts = {t for t, name in run.trajectory.events if name == "touch-down"}
    windows = HoldWindows()
    for r in recs:
        windows.add(r, r.t in impacts)
    return windows.closed + ([] if windows.start is None else [(windows.start, recs[-1].t)])


def jam(run: GraspRun, validity: dict) -> list[str]:
    """Why the grasp is a jam, not a hold (empty: it is not): the bird still
    held off the belt when the run ends, not carried on downstream (moving
    back or at rest on the belt at the end), or a finger past its fold force
    while it carried the bird (design/solvers/grasp/validity.py)."""
    last = run.trajectory.records[-1]
    names = [gf.name for gf in run.setup.grasper.fingers]
    out = []
    if last.mode == "air":
        holding = [n for n, f in zip(names, last.fingers) if f.magnitude > 0]
        out.append(f"the bird is still held off the belt when the run ends at {last.t:.3f} s"
                   + (f" (by {', '.join(holding)})" if holding else ""))
    elif last.y[3] <= 0.0:
        out.append(f"the bird is not carried on: it moves at {last.y[3]:+.3f} m/s along the "
                   f"belt when the run ends")
    out += [f"finger {b['finger']} pressed {b['force_N']:.1f} N, past its fold force "
            f"{b['fold_force_N']:.1f} N, at {b['time_s']:.3f} s"
            for b in validity["forces_beyond_fold"]]
    return out


def summarise(run: GraspRun) -> dict:
    recs = run.trajectory.records
    windows = hold_windows(run)
    names = [gf.name for gf in run.setup.grasper.fingers]
    force = np.array([[f.magnitude for f in r.fingers] for r in recs])
    peak, when = merged_peaks(force, np.array([r.t for r in recs]), run.trajectory.peaks)
    j = int(np.argmax(peak))
    z = np.array([r.y[1] for r in recs])
    gap = z - np.array([BirdDynamics(run.setup.bird, run.setup.legs, 0.0).support(r.y[2])[1]
                        for r in recs])
    validity = contact_validity(run, peak, when)
    jammed = jam(run, validity)
    # a window counts as a hold only if the bird is put back on the belt after it
    # and carried on: not one still open when the run ends, none if the bird stays
    released = [(a, b) for a, b in windows if b < recs[-1].t]
    carried = recs[-1].mode != "air" and recs[-1].y[3] > 0.0
    counted = released if carried else []
    return {
        "hold_windows": [[a, b] for a, b in windows],
        "hold_time_s": max((b - a for a, b in counted), default=0.0),
        "total_hold_s": sum(b - a for a, b in counted),
        "jammed": bool(jammed),
        "jam": jammed,
        "max_finger_force_N": float(peak[j]),
        "max_finger_force_finger": names[j],
        "max_finger_force_time_s": float(when[j]),
        "max_force_per_finger_N": {n: float(v) for n, v in zip(names, peak)},
        "centre_rise_m": float(z.max() - z[0]),
        "belt_clearance_m": float(gap.max()),
        "max_pitch_rad": float(np.max(np.abs([r.y[2] for r in recs]))),
        "min_normal_force_N": float(min(r.normal for r in recs)),
        "finger_model": run.setup.finger_model,
        "validity": validity,
        "belt_contacts": belt_contacts(run),
        "events": [[t, name] for t, name in run.trajectory.events],
        # fixed-step (bdf4) runs only: the adaptive integrator controls its error
        "local_error_estimate": None if run.trajectory.local_error is None else {
            "position_m": run.trajectory.local_error[0],
            "time_s": run.trajectory.local_error[1]},
        "ok": run.trajectory.ok,
        "message": run.trajectory.message,
        "stopped": run.trajectory.stopped or None,
    }
