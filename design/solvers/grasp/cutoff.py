"""Ending a run as soon as it shows that it cannot beat a rival design.

A design search compares each candidate's run with the design it stands at:
a candidate beats it only with every finger under its limit (the cap or the
finger's fold force, the lower) and a longer hold. A run that shows either
cannot be had ends there, whatever the rest of it would do:

* a finger's force at an accepted instant is over its limit: the run's peak
  force is at least that;
* the longest hold the run can still reach is no longer than the rival's:
  the longest window closed so far, the open window run on to the end of the
  run, a window opened later and run to the end.

Both are upper bounds on what the whole run would show, so the search's
decisions are those it takes on whole runs.
"""

from __future__ import annotations

from dataclasses import dataclass

from design.solvers.grasp.simulation import HoldWindows
from design.solvers.grasp.validity import finger_limits


@dataclass(frozen=True)
class Cutoff:
    """The rival a run must be able to beat: its hold (s) and the cap (N)."""

    hold: float
    cap: float

    def watch(self, setup):
        """A watch for the run of ``setup`` (design/solvers/grasp/integrate.py's
        ``Trajectory.watch``): why it ends at its last record, or ""."""
        limits = finger_limits(setup, self.cap)
        names = [gf.name for gf in setup.grasper.fingers]
        windows, impacts, seen = HoldWindows(), set(), [0, 0]

        def reason(traj) -> str:
            impacts.update(t for t, name in traj.events[seen[1]:] if name == "touch-down")
            seen[1] = len(traj.events)
            for r in traj.records[seen[0]:]:
                windows.add(r, r.t in impacts)
                for name, f, limit in zip(names, r.fingers, limits):
                    if f.magnitude > limit:
                        return (f"finger {name} pressed {f.magnitude:.2f} N, over its limit "
                                f"{limit:.2f} N, at {r.t:.3f} s")
            seen[0] = len(traj.records)
            t = traj.records[-1].t
            reach = max([b - a for a, b in windows.closed]
                        + [setup.duration - (t if windows.start is None else windows.start)])
            if reach <= self.hold:
                return (f"it can hold at most {reach:.4f} s from {t:.3f} s on, no longer "
                        f"than the {self.hold:.4f} s to beat")
            return ""
        return reason
