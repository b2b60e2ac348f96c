"""The spatial finger's rod mesh in a grasp: error and cost against intervals.

The grasp scene's ``solver.contact_nodes`` sets the collocation intervals
(degree 4) of every finger's rod. For the two validation scenes that use the
spatial model, the arriving mean bird with soft lower fingers (Table 5-3)
and the football (Table 5-4, designed phase, upper fingers tilted to it),
each mesh's hold time, peak finger force and centre rise are compared with a
10-interval reference, and its CPU time with the default mesh's (6
intervals) in the same run. Every run is warm: a first run at each mesh
builds its CasADi functions and is not timed. The planar finger's cost does
not depend on the mesh this way (its Newton steps cost little; 0.9-1.3 s per
simulated second from 2 to 10 intervals), so it is not in the table.

Prints a table and writes benchmarks/results/spatial_mesh.json (about 4
minutes on 2 cores).

    python -m benchmarks.spatial_mesh
"""

from __future__ import annotations

import os
import time
from pathlib import Path

from benchmarks.results_file import machine, write_results
from design.reproduce.grasp import football_setup, mean_bird_setup
from design.solvers.grasp.integrate import IntegratorSettings
from design.solvers.grasp.simulation import simulate_grasp

RESULTS = Path(__file__).parent / "results" / "spatial_mesh.json"
MESHES = (2, 3, 4, 6)
REFERENCE, DEFAULT = 10, 6
SCENES = {"mean bird, soft lower fingers, arriving": lambda: mean_bird_setup("soft"),
          "football, µ = 1.16": football_setup}


def run(setup, intervals: int) -> dict:
    """One warm run at ``intervals``: its summary numbers and CPU time."""
    simulate_grasp(setup, IntegratorSettings(), intervals)
    cpu = time.process_time()
    result = simulate_grasp(setup, IntegratorSettings(), intervals)
    cpu = time.process_time() - cpu
    s = result.summary
    return {"intervals": intervals, "cpu_s": cpu, "ok": result.trajectory.ok,
            "hold_time_s": s["hold_time_s"], "max_finger_force_N": s["max_finger_force_N"],
            "max_finger_force_finger": s["max_finger_force_finger"],
            "centre_rise_m": s["centre_rise_m"], "steps": result.trajectory.steps}


def scene_rows(setup) -> list[dict]:
    ref = run(setup, REFERENCE)
    rows = [run(setup, n) for n in MESHES] + [ref]
    default = next(r for r in rows if r["intervals"] == DEFAULT)
    for r in rows:
        r["hold_error_s"] = r["hold_time_s"] - ref["hold_time_s"]
        r["peak_relative_error"] = r["max_finger_force_N"] / ref["max_finger_force_N"] - 1
        r["rise_error_m"] = r["centre_rise_m"] - ref["centre_rise_m"]
        r["cpu_over_default"] = r["cpu_s"] / default["cpu_s"]
    return rows


def main() -> None:
    load = os.getloadavg()
    scenes = {}
    print(f"{'scene':42s} {'intervals':>9s} {'hold s':>9s} {'err s':>9s} {'peak N':>8s} "
          f"{'err':>9s} {'rise mm':>8s} {'CPU s':>6s} {'x default':>9s}")
    for name, make in SCENES.items():
        scenes[name] = rows = scene_rows(make())
        for r in rows:
            mark = "" if r["ok"] else "  <- not ok"
            print(f"{name:42s} {r['intervals']:9d} {r['hold_time_s']:9.5f} "
                  f"{r['hold_error_s']:+9.1e} {r['max_finger_force_N']:8.3f} "
                  f"{r['peak_relative_error']:+9.1e} {1e3 * r['centre_rise_m']:8.2f} "
                  f"{r['cpu_s']:6.1f} {r['cpu_over_default']:8.2f}x{mark}", flush=True)
    write_results(RESULTS, {
        "machine": machine(load, at_end=True),
        "reference_intervals": REFERENCE, "default_intervals": DEFAULT, "degree": 4,
        "scenes": scenes})


if __name__ == "__main__":
    main()
