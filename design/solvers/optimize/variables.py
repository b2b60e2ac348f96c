"""Design variables: which parameters of a grasp the optimiser may change.

Every parameter has a name and an SI value in the baseline design:

* ``fingers.<name>.angle | phi_x | phi_y | length | height`` (rad, m);
* ``groups.<group>.stiffness_scale``: EI(s) of every finger of the group
  multiplied by this factor (a new E for the same shape);
* ``conveyor.start_time | rate | final_speed`` (s, m/s², m/s): the belt
  slows from its speed at ``rate`` to ``final_speed`` from ``start_time`` on;
* ``drum_speed`` (rad/s), ``spacing`` (m, between the drum axes).

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
CONVEYOR_FIELDS = {"start_time": "s", "rate": "m/s^2", "final_speed": "m/s"}
GLOBAL_FIELDS = {"drum_speed": "rad/s", "spacing": "m"}


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
    values.update({"conveyor.start_time": c.start_time, "conveyor.rate": c.rate,
                   "conveyor.final_speed": c.final_speed, "drum_speed": setup.drum_speed,
                   "spacing": setup.grasper.spacing})
    return values


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
        return out

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


def apply(setup: GraspSetup, values: dict) -> GraspSetup:
    """The grasp with these parameter values (SI)."""
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
    conveyor = Conveyor(c.speed, values["conveyor.final_speed"], values["conveyor.rate"],
                        values["conveyor.start_time"])
    return replace(setup, grasper=grasper, conveyor=conveyor, drum_speed=values["drum_speed"])
