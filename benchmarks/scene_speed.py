"""The main job's scene: wall time per simulated second.

The scene of problems/hold_time.yaml (the arriving mean bird, every finger a
spatial rod, finger 5 on the belt) at the baseline design, simulated as the
pattern search simulates it (rtol 1e-6, steps up to 5 ms) and at the
scene's own settings (what ``design simulate`` runs: the baseline a user
would otherwise have), both warm (a first run of each builds its functions
and is not timed), setup included, the median of five runs taken in turn
(the machine's load falls on both alike). The target is 1 s of wall time
per simulated second, the goal 0.5 s.

Prints a table and writes benchmarks/results/scene_speed.json.

    python -m benchmarks.scene_speed
"""

from __future__ import annotations

import os
import statistics
import time
from pathlib import Path

import design  # noqa: F401  first: it sets one BLAS thread before numpy loads (design/__init__.py)

from benchmarks.results_file import machine, write_results
from design.io.scene import load_scene
from design.run.grasp import setup_of
from design.solvers.grasp.simulation import simulate_grasp

ROOT = Path(__file__).resolve().parents[1]
RESULTS = Path(__file__).parent / "results" / "scene_speed.json"
PROBLEM = ROOT / "problems" / "hold_time.yaml"
REPEAT = 5
TARGET, GOAL = 1.0, 0.5


def main() -> None:
    problem = load_scene(PROBLEM)
    scene = problem.scene
    settings = problem.settings
    setup = setup_of(scene)
    load = os.getloadavg()
    variants = (("pattern search's settings", settings.simulator),
                ("the scene's own settings (design simulate)", scene.settings.integrator))

    def once(integrator):
        t0 = time.perf_counter()
        run = simulate_grasp(setup, integrator, settings.contact_nodes)
        return time.perf_counter() - t0, run

    for _, integrator in variants:
        once(integrator)                                # warm: builds its functions
    # interleaved, so that a change in the machine's load falls on both alike
    timed = [[once(integrator) for _, integrator in variants] for _ in range(REPEAT)]
    rows = []
    for k, (label, integrator) in enumerate(variants):
        walls = [t[k][0] for t in timed]
        run = timed[-1][k][1]
        s = run.summary
        wall = statistics.median(walls)
        rows.append({"simulator": label, "rtol": integrator.rtol,
                     "max_step_s": integrator.max_step, "wall_s": wall,
                     "walls_s": walls, "simulated_s": setup.duration,
                     "wall_per_simulated_s": wall / setup.duration,
                     "hold_time_s": s["hold_time_s"], "max_finger_force_N": s["max_finger_force_N"],
                     "steps": run.trajectory.steps, "contact_solves": run.contact_solves})
    print(f"{'settings':44s} {'wall (s)':>8s} {'per simulated s':>15s} {'/ scene settings':>17s} "
          f"{'hold (s)':>12s} {'peak (N)':>12s}")
    for r in rows:
        r["over_scene_settings"] = r["wall_s"] / rows[-1]["wall_s"]
        print(f"{r['simulator']:44s} {r['wall_s']:8.2f} {r['wall_per_simulated_s']:15.2f} "
              f"{r['over_scene_settings']:17.3f} {r['hold_time_s']:12.9f} "
              f"{r['max_finger_force_N']:12.8f}")
    print(f"\ntarget {TARGET:g} s per simulated second, goal {GOAL:g}")
    write_results(RESULTS, {
        "machine": machine(load, at_end=True),
        "problem": str(PROBLEM.relative_to(ROOT)), "repeat": REPEAT,
        "target_wall_per_simulated_s": TARGET, "goal_wall_per_simulated_s": GOAL,
        "rows": rows})


if __name__ == "__main__":
    main()
