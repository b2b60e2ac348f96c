"""Beam scenes (``kind: beam``): one finger under one or more point loads.

.. code-block:: yaml

    kind: beam
    finger: models/fingers/thesis_nonuniform_soft.yaml   # or inline
    load: {F: 15, alpha: "90 deg", at: 0.0762}          # F may be a list (a sweep)
    solver: {method: collocation, nodes: 16}            # frisch-fay | small-deflection |
                                                        # shooting | fdm | collocation
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from design.io.fingers import read_finger
from design.io.reader import Reader, join
from design.physics.beam import Finger, PointLoad
from design.solvers.beam import DEFAULT_METHOD, METHODS


@dataclass(frozen=True)
class BeamSolverSettings:
    """Which beam method, and its resolution."""

    #: one of :data:`design.solvers.beam.METHODS`
    method: str = DEFAULT_METHOD
    #: method resolution (intervals, steps or points; None: the method's default)
    nodes: int | None = None
    #: Newton tolerance (None: the method's default)
    tolerance: float | None = None
    #: collocation polynomial degree (None: 4)
    degree: int | None = None

    def options(self) -> dict:
        opts = {"nodes": self.nodes, "tolerance": self.tolerance}
        if self.method == "collocation":
            opts["degree"] = self.degree
        return opts


@dataclass(frozen=True)
class BeamScene:
    """A finger and the loads to solve it under."""

    name: str
    finger: Finger
    loads: tuple[PointLoad, ...]
    solver: BeamSolverSettings
    description: str = ""


def read_beam_solver(reader: Reader, data: dict, field: str, finger: Finger | None
                     ) -> BeamSolverSettings | None:
    """The ``solver`` section of a beam scene."""
    if field not in data:
        return BeamSolverSettings()
    spec = reader.mapping(data[field], field, optional=("method", "nodes", "tolerance", "degree"))
    if spec is None:
        return None
    method = reader.choice(spec, "method", field, METHODS, default=DEFAULT_METHOD)
    nodes = reader.integer(spec, "nodes", field, lo=4, hi=200000, default=None)
    tol = reader.quantity(spec, "tolerance", field, "dimensionless", lo=1e-15, hi=1e-3,
                          default=None)
    degree = reader.integer(spec, "degree", field, lo=1, hi=9, default=None)
    if degree is not None and method != "collocation":
        reader.add(join(field, "degree"), "only the collocation method has a degree")
    if method is not None and finger is not None:
        for reason in METHODS[method](finger).check():
            reader.add(join(field, "method"), reason)
    if method is None:
        return None
    return BeamSolverSettings(method, nodes, tol, degree)


def read_beam(reader: Reader, data: dict, base_dir: Path, name: str) -> BeamScene | None:
    """A beam scene from its parsed YAML mapping (top-level keys already checked)."""
    finger = read_finger(reader, data["finger"], "finger", base_dir) if "finger" in data else None
    loads = None
    if "load" in data:
        spec = reader.mapping(data["load"], "load", required=("F", "alpha"), optional=("at",))
        if spec is not None:
            forces = reader.quantities(spec, "F", "load", "force", lo=0.0)
            alpha = reader.quantity(spec, "alpha", "load", "angle", lo=-np.pi, hi=np.pi)
            hi = finger.length if finger is not None else None
            at = reader.quantity(spec, "at", "load", "length", lo=0.0, hi=hi, lo_open=True,
                                 default=hi)
            if forces is not None and alpha is not None and at is not None:
                loads = tuple(PointLoad(f, alpha, at) for f in forces)
    solver = read_beam_solver(reader, data, "solver", finger)
    if not reader.ok or finger is None or loads is None or solver is None:
        return None
    return BeamScene(name, finger, loads, solver, data.get("description", ""))
