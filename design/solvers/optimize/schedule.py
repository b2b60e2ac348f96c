"""The hybrid schedule of a simulated grasp: the optimiser's phases.

The grasp is a hybrid system: the belt contact is in one of three modes
(stick, slip, air) and every finger is out of contact, in contact along its
span or at its tip, with its friction one way or the other. The optimiser
keeps this *sequence* from a forward simulation of the current design and
moves everything else: phase durations (their ends are the simulation's
events: lift-off N = 0, touch-down, stick/slip), states, design. Finger
contacts are assigned per time-grid stage from the simulation at the
nominal stage time; a contact that would open in the NLP has its force
clipped at zero, a new one is found by the next simulation (the outer loop
rebuilds the schedule around every accepted design).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from design.solvers.grasp.simulation import GraspRun

#: phase ends: the simulation's events. Where the simulator decided the belt
#: mode again (a finger's friction turned and the forces jumped) the end is
#: named by the modes it joins and is not exact: the NLP then asks only that
#: the old mode be over (an inequality), not that it end smoothly
EVENTS = ("lift-off", "touch-down", "slip", "stick")
#: which end a merged phase keeps
PRIORITY = ("touch-down", "lift-off", "slip", "stick")
#: phases shorter than this (s) are merged into their neighbours (the belt
#: touched twice within a fraction of a millisecond, say)
MIN_PHASE = 1e-3
#: RK4 stage offsets within an interval
STAGES = (0.0, 0.5, 0.5, 1.0)


@dataclass(frozen=True)
class FingerContact:
    """A finger's contact at one stage: mode ``interior`` or ``tip``, signed
    friction τµ (planar fingers; 0 for spatial ones, whose friction follows
    their sliding), and the collocation unknowns z of the simulation as a
    guess."""

    mode: str
    tau_mu: float
    z: np.ndarray


@dataclass
class Phase:
    """One belt mode between two events: mode, slip sign (±1 in slip), the
    simulated start and end (s), how it ends, and its time grid."""

    mode: str
    sign: float
    t0: float
    t1: float
    end: str
    #: the end is an event located by the simulator (else a re-decision)
    exact: bool = True
    intervals: int = 1
    #: contacts[k][s][i]: finger i at stage s of interval k (None: no contact)
    contacts: list = field(default_factory=list)
    #: the simulated state (intervals, 6) at each interval's start node
    states: np.ndarray | None = None

    @property
    def duration(self) -> float:
        return self.t1 - self.t0


@dataclass
class Schedule:
    """Phases covering [t_start, t_end]; ``hold`` indexes the air phase whose
    duration is the hold time."""

    phases: list[Phase]
    hold: int
    t_start: float
    t_end: float

    @property
    def intervals(self) -> int:
        return sum(p.intervals for p in self.phases)


def schedule_of(run: GraspRun, time_step: float, margin: float = 0.05) -> Schedule:
    """The phases of a simulation, gridded with intervals of about
    ``time_step`` (s), over the fingers' contact period padded by ``margin``."""
    recs = run.trajectory.records
    times = np.array([r.t for r in recs])
    ys = np.array([r.y for r in recs])
    touching = [r.t for r in recs if any(f.solution is not None and f.solution.contact
                                          for f in r.fingers)]
    if not touching:
        raise ValueError("no finger touches the bird in the simulation: nothing to design")
    keys = [_key(r) for r in recs]
    first_change = next((r.t for r, k in zip(recs, keys) if k != keys[0]), recs[-1].t)
    # before t_start the bird rides the belt at rest on it: no finger, no change
    # of belt mode, and a belt at constant speed (slowing, it would roll the bird)
    conveyor = run.setup.conveyor
    slows = conveyor.start_time if conveyor.decelerates and \
        conveyor.final_speed < conveyor.speed else np.inf
    t_start = max(0.0, min(touching[0], first_change, slows) - margin)
    events = {round(t, 12): name for t, name in run.trajectory.events if name in EVENTS}
    phases: list[Phase] = []
    k0 = int(np.searchsorted(times, t_start, side="right")) - 1
    mode, sign = keys[k0]
    start = t_start
    for r, key in zip(recs[k0 + 1:], keys[k0 + 1:]):
        event = events.get(round(r.t, 12))
        if (key != (mode, sign) or event) and r.t > start:
            phases.append(Phase(mode, sign, start, r.t, event or _joining((mode, sign), key),
                                exact=event is not None))
            mode, sign, start = key[0], key[1], r.t
    phases.append(Phase(mode, sign, start, recs[-1].t, "end"))
    phases = _merge_short(phases)
    airs = [i for i, p in enumerate(phases) if p.mode == "air" and p.end != "end"]
    if not airs:
        raise ValueError("the bird never leaves the belt and comes back in the simulation: no "
                         "hold phase to lengthen (start from a design that lifts it, or run "
                         "longer)")
    hold = max(airs, key=lambda i: phases[i].duration)
    t_end = min(recs[-1].t, max(touching[-1], phases[hold].t1) + margin)
    phases = [p for p in phases if p.t0 < t_end]
    phases[-1].t1, phases[-1].end = t_end, "end"
    for p in phases:
        p.intervals = max(1, int(round(p.duration / time_step)))
        p.contacts = [[_contacts(recs, times, p.t0 + (k + c) * p.duration / p.intervals)
                       for c in STAGES] for k in range(p.intervals)]
        nodes = p.t0 + np.arange(p.intervals) * p.duration / p.intervals
        p.states = np.stack([np.interp(nodes, times, ys[:, j]) for j in range(6)], axis=1)
    return Schedule(phases, hold, t_start, t_end)


def _key(record) -> tuple[str, float]:
    if record.mode == "slip":             # F_c = -µ N sgn(slip)
        return "slip", -float(np.sign(record.friction * record.normal)) or 1.0
    return record.mode, 0.0


def _merge_short(phases: list[Phase]) -> list[Phase]:
    """Drop phases shorter than MIN_PHASE: the previous phase runs into the
    next one and ends with the more decisive of the two events (a double
    touch-down becomes one; slip, a moment's stick, lift-off becomes slip,
    lift-off)."""
    out: list[Phase] = []
    for p in phases:
        if out and p.duration < MIN_PHASE and p.end != "end":
            if PRIORITY.index(p.end) < PRIORITY.index(out[-1].end):
                out[-1].end, out[-1].exact = p.end, p.exact
            continue
        if out:
            out[-1].t1 = p.t0
            if (out[-1].mode, out[-1].sign) == (p.mode, p.sign) and out[-1].end != "touch-down":
                out[-1].t1, out[-1].end, out[-1].exact = p.t1, p.end, p.exact
                continue
        out.append(p)
    return out


def _joining(before: tuple[str, float], after: tuple[str, float]) -> str:
    """The event that joins two belt modes: leaving the belt is a lift-off,
    reaching it a touch-down, stick to slip a slip; anything else (slip to
    stick, slip reversing) passes through zero slip: a stick."""
    if after[0] == "air":
        return "lift-off"
    if before[0] == "air":
        return "touch-down"
    return "slip" if before[0] == "stick" else "stick"


def _contacts(recs, times, t: float) -> list[FingerContact | None]:
    """Each finger's contact in the record nearest to t."""
    k = int(np.clip(np.searchsorted(times, t), 1, len(times) - 1))
    r = recs[k] if abs(times[k] - t) < abs(times[k - 1] - t) else recs[k - 1]
    out = []
    for f in r.fingers:
        s = f.solution
        if s is None or not s.contact or "z" not in s.extras:
            out.append(None)
        else:
            # the spatial finger's friction follows its sliding: no sense to keep
            out.append(FingerContact(s.extras["mode"], s.extras.get("friction_ratio", 0.0),
                                     np.asarray(s.extras["z"], float)))
    return out
