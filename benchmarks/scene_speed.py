"""Spatial grasp scenes: wall time per simulated second.

The scene of problems/hold_time.yaml (the arriving mean bird, every finger a
spatial rod, finger 5 on the belt) at the baseline design, simulated as the
pattern search simulates it (rtol 1e-6, steps up to 5 ms) and at the
scene's own settings (what ``design simulate`` runs: the baseline a user
would otherwise have); and the football scene (problems/grasp_football.yaml)
at its own settings (the implicit radau stepper: its fingers' regularised
friction is stiff) and with the default stepper, rk45. Each warm (a first
run of each builds its functions and is not timed), setup included, the
median of five runs taken in turn (the machine's load falls on all alike).
The target is 1 s of wall time per simulated second, the goal 0.5 s.

Prints a table and writes benchmarks/results/scene_speed.json.

    python -m benchmarks.scene_speed
"""

from __future__ import annotations

import os
import statistics
import time
from dataclasses import replace
from pathlib import Path

import design  # noqa: F401  first: it sets one BLAS thread before numpy loads (design/__init__.py)

from benchmarks.results_file import machine, write_results
from design.io.scene import load_scene
from design.run.grasp import setup_of
from design.solvers.grasp.simulation import simulate_grasp

ROOT = Path(__file__).resolve().parents[1]
RESULTS = Path(__file__).parent / "results" / "scene_speed.json"
PROBLEM = ROOT / "problems" / "hold_time.yaml"
FOOTBALL = ROOT / "problems" / "grasp_football.yaml"
REPEAT = 5
TARGET, GOAL = 1.0, 0.5


def main() -> None:
    problem = load_scene(PROBLEM)
    scene = problem.scene
    settings = problem.settings
    football = load_scene(FOOTBALL)
    main_job = ("the main job's scene", setup_of(scene), settings.contact_nodes)
    ball = ("the football", setup_of(football), football.settings.contact_nodes)
    own = football.settings.integrator
    load = os.getloadavg()
    variants = ((main_job, "pattern search's settings", settings.simulator),
                (main_job, "the scene's own settings (design simulate)", scene.settings.integrator),
                (ball, f"the scene's own settings (design simulate, {own.stepper})", own),
                (ball, "the default stepper, rk45", replace(own, stepper="rk45")))

    def once(case, integrator):
        """The run's wall time and what the table reports of it; the run
        itself is dropped, as a user's process would: keeping every run's
        states (about 80 MB each) slows the later runs' allocations."""
        _, setup, nodes = case
        t0 = time.perf_counter()
        run = simulate_grasp(setup, integrator, nodes)
        return time.perf_counter() - t0, (run.summary, run.trajectory.steps, run.contact_solves)

    for case, _, integrator in variants:
        once(case, integrator)                          # warm: builds its functions
    # interleaved, so that a change in the machine's load falls on all alike
    timed = [[once(case, integrator) for case, _, integrator in variants] for _ in range(REPEAT)]
    rows = []
    for k, ((name, setup, _), label, integrator) in enumerate(variants):
        walls = [t[k][0] for t in timed]
        s, steps, solves = timed[-1][k][1]
        wall = statistics.median(walls)
        rows.append({"scene": name, "simulator": label, "stepper": integrator.stepper,
                     "rtol": integrator.rtol, "max_step_s": integrator.max_step, "wall_s": wall,
                     "walls_s": walls, "simulated_s": setup.duration,
                     "wall_per_simulated_s": wall / setup.duration,
                     "hold_time_s": s["hold_time_s"], "max_finger_force_N": s["max_finger_force_N"],
                     "steps": steps, "contact_solves": solves})
    for r in rows:
        r["over_scene_settings"] = r["wall_s"] / next(
            o["wall_s"] for o in rows if o["scene"] == r["scene"] and "own" in o["simulator"])
    print(f"{'scene':22s} {'settings':52s} {'wall (s)':>8s} {'per simulated s':>15s} "
          f"{'/ scene settings':>17s} {'hold (s)':>12s} {'peak (N)':>12s}")
    for r in rows:
        print(f"{r['scene']:22s} {r['simulator']:52s} {r['wall_s']:8.2f} "
              f"{r['wall_per_simulated_s']:15.2f} "
              f"{r['over_scene_settings']:17.3f} {r['hold_time_s']:12.9f} "
              f"{r['max_finger_force_N']:12.8f}")
    print(f"\ntarget {TARGET:g} s per simulated second, goal {GOAL:g}")
    write_results(RESULTS, {
        "machine": machine(load, at_end=True),
        "problem": str(PROBLEM.relative_to(ROOT)), "football": str(FOOTBALL.relative_to(ROOT)),
        "repeat": REPEAT,
        "target_wall_per_simulated_s": TARGET, "goal_wall_per_simulated_s": GOAL,
        "rows": rows})


if __name__ == "__main__":
    main()
