"""Running a beam scene: solve every load with the chosen method."""

from __future__ import annotations

import time

import numpy as np

from design import __version__
from design.io.beam_scene import BeamScene
from design.physics.beam import BeamSolution
from design.run import Progress, RunOutput
from design.solve.beam import make_method


def whole_finger(sol: BeamSolution, length: float) -> dict:
    """The deflected finger from the clamp to its free end (s = ``length``, m):
    the solution up to the load point, then one more point at the end, since
    past the load the finger carries no moment and stays straight."""
    s, x, y, psi, m = sol.s, sol.x, sol.y, sol.psi, sol.moment
    rest = length - sol.load.at
    if rest > 0:
        s, psi, m = np.append(s, length), np.append(psi, psi[-1]), np.append(m, 0.0)
        x = np.append(x, x[-1] + rest * np.cos(psi[-1]))
        y = np.append(y, y[-1] + rest * np.sin(psi[-1]))
    return {"s": s, "x": x, "y": y, "psi": psi, "M": m}


def case_dict(sol: BeamSolution, length: float) -> dict:
    """One load's result, SI units (m, N, rad, N m). ``tip`` is the load point
    (s = ``at``); ``shape`` is the whole finger of ``length`` (m)."""
    fx, fy = sol.load.components
    x, y, psi = sol.tip
    return {
        "F": sol.load.force, "alpha": sol.load.alpha, "at": sol.load.at,
        "tip": {"x": x, "y": y, "psi": psi},
        "shape": whole_finger(sol, length),
        "error_estimate": sol.error_estimate, "converged": sol.converged,
        "branch": sol.branch, "multiple_equilibria": sol.multiple_equilibria,
        "iterations": sol.iterations, "message": sol.message,
        "base_moment": float(sol.moment[0]), "load_moment": x * fy - y * fx,
    }


def run(scene: BeamScene, progress: Progress | None = None) -> RunOutput:
    method = make_method(scene.solver.method, scene.finger, **scene.solver.options())
    if progress and len(scene.loads) > 20:
        progress(f"solving {len(scene.loads)} loads with {method.name}")
    t0 = time.perf_counter()
    sols = method.solve(scene.loads)
    elapsed = time.perf_counter() - t0
    cases = [case_dict(s, scene.finger.length) for s in sols]
    result = {
        "kind": "beam", "name": scene.name, "toolkit_version": __version__,
        "units": {"length": "m", "force": "N", "angle": "rad", "moment": "N m",
                  "time": "s", "EI": "N m^2"},
        "method": method.name,
        "solver": {"method": method.name, "nodes": method.nodes, "tolerance": method.tolerance,
                   **({"degree": method.degree} if hasattr(method, "degree") else {})},
        "finger": scene.finger.describe(),
        "solve_time_s": elapsed,
        "cases": cases,
    }
    rows = [{"F_N": c["F"], "alpha_rad": c["alpha"], "at_m": c["at"], "tip_x_m": c["tip"]["x"],
             "tip_y_m": c["tip"]["y"], "tip_psi_rad": c["tip"]["psi"],
             "error_estimate_m": c["error_estimate"], "converged": c["converged"],
             "branch": c["branch"], "iterations": c["iterations"]} for c in cases]
    shapes = [{"case": i, "s_m": s, "x_m": x, "y_m": y, "psi_rad": p, "M_N_m": m}
              for i, c in enumerate(cases)
              for s, x, y, p, m in zip(*(c["shape"][k] for k in ("s", "x", "y", "psi", "M")))]
    return RunOutput(result, {"cases.csv": rows, "shapes.csv": shapes},
                     ok=all(s.converged for s in sols))
