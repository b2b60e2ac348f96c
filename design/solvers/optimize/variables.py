"""Design variables: which parameters of a grasp the optimiser may change.

Every parameter has a name and an SI value in the baseline design:

* ``fingers.<name>.angle | phi_x | phi_y | length | height`` (rad, m);
* ``groups.<group>.stiffness_scale``: EI(s) of every finger of the group
  multiplied by this factor (a new E for the same shape);
* ``conveyor.start_time | rate | final_speed`` (s, m/s², m/s): the belt
  slows from its speed at ``rate`` to ``final_speed`` from ``start_time`` on;
* ``drum_speed`` (rad/s), ``spacing`` (m, between the drum axes);
* the line: ``drum_speed`` ω, ``conveyor.speed`` v (m/s, the belt's speed
  before it slows) and ``bird_spacing`` Δx (m, between consecutive birds)
  are tied by eq. 5.3, 2π v = n Δx ω (n finger sets): at most two of them
  are variables and the third follows (Δx if it is not one, else v). A
  line that moves keeps the bird meeting its finger set as in the baseline
  scene: the bird starts Δx upstream of where the baseline's bird is one
  finger-set period 2π/(nω) after the start; the run lasts that period plus
  the baseline's time after it or the time the drum takes to turn as far,
  whichever is longer (a faster drum turns further, a slower one as far,
  and the bird always has the baseline's time to fall back onto the belt);
  a belt that does not slow stays at its new speed (one that slows keeps
  its final speed, rate and start).

A :class:`DesignSpace` lists the variables with bounds; the optimiser works
on scaled variables d ∈ [0, 1] (d = 0 the lower bound), numbers or CasADi
symbols; parameters not listed stay at the baseline value.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from design.physics.bird import Conveyor
from design.physics.kinematics import FingerMount
from design.solvers.grasp.simulation import GraspSetup

FINGER_FIELDS = {"angle": "rad", "phi_x": "rad", "phi_y": "rad", "length": "m", "height": "m"}
GROUP_FIELDS = {"stiffness_scale": "1"}
CONVEYOR_FIELDS = {"speed": "m/s", "start_time": "s", "rate": "m/s^2", "final_speed": "m/s"}
GLOBAL_FIELDS = {"drum_speed": "rad/s", "spacing": "m", "bird_spacing": "m"}
#: the line's parameters tied by eq. 5.3, in the order the one that follows
#: from the others is chosen (the first that is not a variable)
LINE = ("bird_spacing", "conveyor.speed", "drum_speed")


@dataclass(frozen=True)
class Variable:
    """A design variable: parameter name, bounds (SI) and baseline value."""

    name: str
    lo: float
    hi: float
    baseline: float

    @property
    def unit(self) -> str:
        return units(self.name)


def units(name: str) -> str:
    field = name.rsplit(".", 1)[-1]
    for table in (FINGER_FIELDS, GROUP_FIELDS, CONVEYOR_FIELDS, GLOBAL_FIELDS):
        if field in table:
            return table[field]
    raise KeyError(name)


def timed_conveyor(conveyor: Conveyor, start_time: float | None) -> Conveyor:
    """The belt with its deceleration started at a time (a position-triggered
    start converted by the caller from a simulation); a constant belt
    becomes one that 'slows' to its own speed."""
    if not conveyor.decelerates:
        return Conveyor(conveyor.speed, conveyor.speed, conveyor.rate, 0.0)
    return Conveyor(conveyor.speed, conveyor.final_speed, conveyor.rate, start_time)


def parameters_of(setup: GraspSetup) -> dict[str, float]:
    """Every parameter of a grasp, by name (SI). The conveyor must be timed."""
    values: dict[str, float] = {}
    for gf in setup.grasper.fingers:
        m, key = gf.mount, f"fingers.{gf.design_name}."
        values.update({key + "angle": m.angle - gf.phase, key + "phi_x": m.phi_x,
                       key + "phi_y": m.phi_y, key + "height": m.height,
                       key + "length": gf.finger.length})
    for group in groups(setup):
        values[f"groups.{group}.stiffness_scale"] = 1.0
    c = setup.conveyor
    values.update({"conveyor.speed": c.speed, "conveyor.start_time": c.start_time,
                   "conveyor.rate": c.rate, "conveyor.final_speed": c.final_speed,
                   "drum_speed": setup.drum_speed, "spacing": setup.grasper.spacing,
                   "bird_spacing": bird_spacing(c.speed, setup.drum_speed, setup.grasper.sets)})
    return values


def bird_spacing(speed: float, drum_speed: float, sets: int):
    """Δx (m) of eq. 5.3, 2π v = n Δx ω, at belt speed v (m/s), drum speed ω
    (rad/s) and n finger sets."""
    return 2 * np.pi * speed / (sets * drum_speed)


def tied(values: dict, base: dict, follows: str) -> dict:
    """``values`` with the line parameter ``follows`` (one of :data:`LINE`)
    set by eq. 5.3 from the other two, as its ``base`` value times their
    ratios to theirs (exactly the base value where they are theirs)."""
    out = dict(values)
    ratio = {name: out[name] / base[name] for name in LINE}
    out[follows] = base[follows] * {
        "bird_spacing": lambda r: r["conveyor.speed"] / r["drum_speed"],
        "conveyor.speed": lambda r: r["bird_spacing"] * r["drum_speed"],
        "drum_speed": lambda r: r["conveyor.speed"] / r["bird_spacing"]}[follows](ratio)
    return out


def groups(setup: GraspSetup) -> list[str]:
    return sorted({gf.group for gf in setup.grasper.fingers})


class DesignSpace:
    """The variables of a design problem around a baseline grasp."""

    def __init__(self, baseline: GraspSetup, variables: list[Variable]):
        self.baseline = baseline
        self.variables = list(variables)
        self.base_values = parameters_of(baseline)
        for v in self.variables:
            if v.name not in self.base_values:
                raise KeyError(v.name)
        names = {v.name for v in self.variables}
        line = [n for n in LINE if n in names]
        if len(line) == len(LINE):
            raise ValueError(f"{', '.join(LINE)} are tied by eq. 5.3: at most two of them "
                             "may be variables")
        #: the line parameter that follows from the others (None: the line is fixed)
        self.follows = next(n for n in LINE if n not in names) if line else None

    @property
    def size(self) -> int:
        return len(self.variables)

    @property
    def lower(self) -> np.ndarray:
        return np.array([v.lo for v in self.variables])

    @property
    def upper(self) -> np.ndarray:
        return np.array([v.hi for v in self.variables])

    def values(self, d) -> dict:
        """All parameters at scaled variables d (numbers or CasADi symbols)."""
        out = dict(self.base_values)
        for i, v in enumerate(self.variables):
            out[v.name] = v.lo + d[i] * (v.hi - v.lo)
        return tied(out, self.base_values, self.follows) if self.follows else out

    def scale(self, values: dict) -> np.ndarray:
        """Scaled variables of a numeric design, clipped to [0, 1]."""
        return np.clip([(values[v.name] - v.lo) / (v.hi - v.lo) for v in self.variables], 0, 1)

    def design(self, d: np.ndarray) -> dict[str, float]:
        """The variables' SI values at scaled d."""
        vals = self.values(d)
        return {v.name: float(vals[v.name]) for v in self.variables}

    def setup(self, d: np.ndarray) -> GraspSetup:
        """The grasp at scaled variables d, for the simulator."""
        return apply(self.baseline, self.values(np.asarray(d, float)))

    def finger_change(self, a: np.ndarray, b: np.ndarray) -> tuple[set[int], set[int]] | None:
        """Where scaled designs a and b differ only in fingers' parameters: the
        fingers (indices) moved or resized, and those whose group's stiffness
        differs; None where another parameter differs."""
        va, vb = self.values(np.asarray(a, float)), self.values(np.asarray(b, float))
        fingers = self.baseline.grasper.fingers
        moved, stiffened = set(), set()
        for name in (n for n in va if va[n] != vb[n]):
            kind, _, rest = name.partition(".")
            owner, _, field = rest.rpartition(".")
            if kind == "fingers" and field in FINGER_FIELDS:
                moved |= {i for i, gf in enumerate(fingers) if gf.design_name == owner}
            elif kind == "groups" and field in GROUP_FIELDS:
                stiffened |= {i for i, gf in enumerate(fingers) if gf.group == owner}
            else:
                return None
        return moved, stiffened

    def scene_key(self, d: np.ndarray) -> tuple:
        """The parameters that act on the grasp at scaled d (:func:`acting`):
        two designs with the same key simulate the same scene."""
        return tuple(sorted(acting(self.values(np.asarray(d, float)), self.baseline).items()))


#: a final speed within this fraction of the belt's speed is its speed
SAME_SPEED = 1e-12


def acting(values: dict, setup: GraspSetup) -> dict:
    """``values`` (SI) as they act on ``setup``'s grasp: a belt that does not
    slow stays at its (new) speed, and one whose final speed is its speed
    has no start or rate to act (start 0 s, ``setup``'s rate)."""
    out, c = dict(values), setup.conveyor
    speed = out["conveyor.speed"]
    if out["conveyor.final_speed"] == c.speed == c.final_speed:
        out["conveyor.final_speed"] = speed
    if abs(out["conveyor.final_speed"] - speed) <= SAME_SPEED * speed:
        out.update({"conveyor.final_speed": speed, "conveyor.start_time": 0.0,
                    "conveyor.rate": c.rate})
    return out


def apply(setup: GraspSetup, values: dict) -> GraspSetup:
    """The grasp with these parameter values (SI)."""
    values = acting(values, setup)
    fingers = []
    for gf in setup.grasper.fingers:
        key = f"fingers.{gf.design_name}."
        scale = values[f"groups.{gf.group}.stiffness_scale"]
        finger = gf.finger if scale == 1.0 else gf.finger.scaled(scale)
        mount = FingerMount(values[key + "angle"] + gf.phase, values[key + "height"],
                            gf.mount.radius, values[key + "phi_x"], values[key + "phi_y"])
        fingers.append(replace(gf, finger=replace(finger, length=values[key + "length"]),
                               mount=mount))
    grasper = replace(setup.grasper, fingers=tuple(fingers), spacing=values["spacing"])
    c = setup.conveyor
    speed, drum_speed = values["conveyor.speed"], values["drum_speed"]
    conveyor = Conveyor(speed, values["conveyor.final_speed"], values["conveyor.rate"],
                        values["conveyor.start_time"])
    out = replace(setup, grasper=grasper, conveyor=conveyor, drum_speed=drum_speed)
    if (speed, drum_speed) == (c.speed, setup.drum_speed):
        return out
    return synchronised(out, setup)


def synchronised(setup: GraspSetup, baseline: GraspSetup) -> GraspSetup:
    """``setup``, whose line (belt and drum speed, finger sets) differs from
    the baseline's, with the bird meeting its finger set as in the
    baseline: it starts Δx upstream of where the baseline's bird is one
    finger-set period after the start, and the run covers the new period
    and the baseline's time or turn of the drum after it, the longer
    (module docstring)."""
    period = 2 * np.pi / (setup.grasper.sets * setup.drum_speed)
    base_period = 2 * np.pi / (baseline.grasper.sets * baseline.drum_speed)
    met = baseline.start_x + baseline.conveyor.speed * base_period
    after = (baseline.duration - base_period) * max(1.0, baseline.drum_speed / setup.drum_speed)
    return replace(setup, start_x=met - setup.conveyor.speed * period,
                   duration=period + after)
