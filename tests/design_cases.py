"""A short grasp for the optimiser's tests: the mean bird through a test
grasper (tests/data/one_set_grasper.yaml: one set of Table 5-1's fingers at
angles read under the superseded convention, whose hold varies smoothly with
the design) on a constant belt from X0 = -0.457 m, started 0.6 s in (fingers
and bird advanced so that nothing touches before), 0.85 s long; the hold is
0.36-0.67 s."""

from __future__ import annotations

import json
from dataclasses import replace

from pathlib import Path

from design.io.grasp_scene import GraspSettings, read_grasper
from design.io.scene_writer import grasp_spec
from design.reproduce.grasp import advanced, load_model, thesis_setup
from design.solve.optimize.variables import DesignSpace, Variable, timed_conveyor

GRASPER = Path(__file__).parent / "data" / "one_set_grasper.yaml"


def short_setup():
    s = thesis_setup(t_skip=0.6, duration=0.85, start=-0.457)
    grasper = advanced(load_model(read_grasper, str(GRASPER)), 0.6)
    return replace(s, grasper=grasper, conveyor=timed_conveyor(s.conveyor, None))


def stiffness_space(*groups: str, lo: float = 0.5, hi: float = 1.5) -> DesignSpace:
    """Group stiffness scales as the variables (baseline 1)."""
    return DesignSpace(short_setup(), [Variable(f"groups.{g}.stiffness_scale", lo, hi, 1.0)
                                       for g in groups])


def short_problem_file(path: Path, variables: dict, **solver) -> Path:
    """Write a design problem on the short grasp (cap: the baseline's peak,
    10 ms grid) to ``path`` (JSON is YAML); ``solver``: further settings."""
    scene = grasp_spec(short_setup(), GraspSettings(contact_nodes=6), "short", "")
    path.write_text(json.dumps({"kind": "design", "scene": scene, "cap": "baseline",
                                "variables": variables,
                                "solver": {"time_step": 0.01, **solver}}))
    return path
