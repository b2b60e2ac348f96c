"""Running a beam scene: solve every load with the chosen method."""

from __future__ import annotations

import time
from collections.abc import Iterator, Sequence

import numpy as np

from design import __version__
from design.io.beam_scene import BeamScene
from design.physics.beam import BeamSolution
from design.run import Progress, RunOutput
from design.solvers.beam import make_method


def whole_fingers(sols: Sequence[BeamSolution], length: float) -> list[dict]:
    """Each solution's deflected finger from the clamp to its free end
    (s = ``length``, m): the solution up to the load point, then one more
    point at the end, since past the load the finger carries no moment and
    stays straight. Solutions with as many nodes and the same load point are
    extended together (a sweep's thousand one by one took longer than solving
    them)."""
    groups: dict[tuple, list[int]] = {}
    for i, sol in enumerate(sols):
        groups.setdefault((sol.s.size, sol.load.at), []).append(i)
    out: list[dict] = [{}] * len(sols)
    for (_, at), members in groups.items():
        s, x, y, psi, m = (np.array([getattr(sols[i], k) for i in members])
                           for k in ("s", "x", "y", "psi", "moment"))
        rest = length - at
        if rest > 0:
            end = psi[:, -1:]
            s = np.hstack([s, np.full_like(end, length)])
            x = np.hstack([x, x[:, -1:] + rest * np.cos(end)])
            y = np.hstack([y, y[:, -1:] + rest * np.sin(end)])
            psi, m = np.hstack([psi, end]), np.hstack([m, np.zeros_like(end)])
        for row, i in enumerate(members):
            out[i] = {"s": s[row], "x": x[row], "y": y[row], "psi": psi[row], "M": m[row]}
    return out


def case_dict(sol: BeamSolution, shape: dict) -> dict:
    """One load's result, SI units (m, N, rad, N m). ``tip`` is the load point
    (s = ``at``); ``shape`` is the whole finger (:func:`whole_fingers`)."""
    fx, fy = sol.load.components
    x, y, psi = sol.tip
    return {
        "F": sol.load.force, "alpha": sol.load.alpha, "at": sol.load.at,
        "tip": {"x": x, "y": y, "psi": psi},
        "shape": shape,
        "error_estimate": sol.error_estimate, "converged": sol.converged,
        "branch": sol.branch, "multiple_equilibria": sol.multiple_equilibria,
        "iterations": sol.iterations, "message": sol.message,
        "base_moment": float(sol.moment[0]), "load_moment": x * fy - y * fx,
    }


class ShapeRows(Sequence):
    """shapes.csv: a row per case and shape point, made when read (written
    to a folder), not with every result (82,000 dicts for a 1000-load sweep
    took longer than solving it)."""

    COLUMNS = {"s_m": "s", "x_m": "x", "y_m": "y", "psi_rad": "psi", "M_N_m": "M"}

    def __init__(self, cases: list[dict]):
        self.shapes = [c["shape"] for c in cases]
        self.first = np.cumsum([0] + [shape["s"].size for shape in self.shapes])

    def __len__(self) -> int:
        return int(self.first[-1])

    def __getitem__(self, i: int) -> dict:
        if not -len(self) <= i < len(self):
            raise IndexError(i)
        i %= len(self)
        case = int(np.searchsorted(self.first, i, side="right")) - 1
        return self._row(case, i - self.first[case])

    def __iter__(self) -> Iterator[dict]:
        for case, shape in enumerate(self.shapes):
            for j in range(shape["s"].size):
                yield self._row(case, j)

    def _row(self, case: int, j: int) -> dict:
        shape = self.shapes[case]
        return {"case": case, **{name: shape[k][j] for name, k in self.COLUMNS.items()}}


def run(scene: BeamScene, progress: Progress | None = None) -> RunOutput:
    method = make_method(scene.solver.method, scene.finger, **scene.solver.options())
    if progress and len(scene.loads) > 20:
        progress(f"solving {len(scene.loads)} loads with {method.name}")
    t0 = time.perf_counter()
    sols = method.solve(scene.loads)
    elapsed = time.perf_counter() - t0
    shapes = whole_fingers(sols, scene.finger.length)
    cases = [case_dict(s, shape) for s, shape in zip(sols, shapes)]
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
    return RunOutput(result, {"cases.csv": rows, "shapes.csv": ShapeRows(cases)},
                     ok=all(s.converged for s in sols))
