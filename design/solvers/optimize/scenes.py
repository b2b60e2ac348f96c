"""Designs scored once per run: a search's design whose simulation would be
one already made takes that one's score.

Two ways a design's run is one simulated before, each exact:

* **the same scene** (:meth:`~design.solvers.optimize.variables.DesignSpace.
  scene_key`): the parameters that act on the grasp are equal; a belt whose
  final speed is its speed has no start or rate to act;
* **the same run**: the design differs from the search's current one only
  in fingers that run never reached. A simulation solves a finger only at
  instants where its straight line enters the bird or its tip rests on the
  belt (design/solvers/grasp/fingers.py, ``FingerForces.reaching``); a
  finger that did not reach the bird at any instant the run looked at
  added nothing to it. If the design's changed fingers, where it puts
  them, stay clear at every one of those instants (``clear_at``, with a
  margin for round-off), its run looks at the same instants, sees the
  same states and leaves the same fingers out: record for record the same
  run. Its limits hold as the current design's: a finger that presses
  nothing is under its fold force, whatever its stiffness.

A candidate so scored holds exactly as long as the current design, so it
does not beat it: the search takes the steps it takes with every run
simulated.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from design.solvers.grasp.fingers import clear_at
from design.solvers.optimize.population import Population
from design.solvers.optimize.trust_region import Scored


def same_run(population: Population, d: np.ndarray, reference: Scored) -> bool:
    """Is the scaled design ``d``'s run, bird by bird, the ``reference``'s
    (a design scored whole: every bird's run to its end)? Where it differs
    only in fingers the reference's runs never reached, which stay clear at
    every instant those runs looked (module docstring)."""
    if reference.ruled_out_by or len(reference.members) != len(population.members):
        return False
    for member, evaluated in zip(population.members, reference.members):
        run = evaluated.run
        change = member.space.finger_change(reference.d, d)
        if change is None or run.probes is None or run.summary.get("stopped"):
            return False
        moved, stiffened = change
        if run.reached & (moved | stiffened):
            return False
        setup = member.space.setup(d)
        if not clear_at(setup.grasper, setup.bird, setup.drum_speed, sorted(moved), run.probes):
            return False
    return True


class Scenes:
    """Designs scored by ``score(designs, incumbent, ahead)`` once per run: a
    design whose ``key`` (its scene) is that of one scored before (or
    earlier in the same call), or whose run is the ``incumbent``'s
    (``same(d, incumbent)``: :func:`same_run`), takes that score without
    a simulation."""

    def __init__(self, score, key, same=lambda d, incumbent: False):
        self._score, self.key, self.same = score, key, same
        self.scored: dict[tuple, Scored] = {}
        #: the designs (their bytes) that took another's score
        self.repeats: set[bytes] = set()

    def _known(self, k: tuple, d: np.ndarray, incumbent: Scored | None) -> bool:
        """Is design d (scene key k) scored already? A design whose run is
        the incumbent's is then scored as it."""
        if k in self.scored:
            return True
        if incumbent is not None and self.same(d, incumbent):
            self.scored[k] = incumbent
            return True
        return False

    def score(self, designs, incumbent: Scored | None = None, ahead=()) -> list[Scored]:
        keys = [self.key(d) for d in designs]
        new: dict[tuple, np.ndarray] = {}
        for k, d in zip(keys, designs):
            if k in new or self._known(k, d, incumbent):
                self.repeats.add(np.asarray(d, float).tobytes())
            else:
                new[k] = d
        later: dict[tuple, np.ndarray] = {}
        for d in ahead:
            later.setdefault(self.key(d), d)
        ahead = [d for k, d in later.items()
                 if k not in new and k not in self.scored
                 and not (incumbent is not None and self.same(d, incumbent))]
        if new:
            self.scored.update(zip(new, self._score(list(new.values()), incumbent, ahead)))
        return [replace(self.scored[k], d=np.asarray(d, float)) for k, d in zip(keys, designs)]

    def repeated(self, d) -> bool:
        """Did design ``d`` take another's score?"""
        return np.asarray(d, float).tobytes() in self.repeats
