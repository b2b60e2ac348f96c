"""Quick start: the toolkit's Python API in a few seconds.

    python examples/quickstart.py

1. Simulate a grasp given as a Python dict (a scene file's content,
   docs/guide.md): the thesis's mean bird placed on a small grasper, one
   set of Table 5-1's fingers 3 and 4 on each drum, for half a second.
2. Read the run's summary and its time series.
3. Optimise a two-variable design problem on that scene (the lower
   fingers' stiffness and finger 4's angle; no finger may press harder than
   the baseline's peak) with a few Ipopt iterations, and print its verdict.

Results are SI, with the unit in each name (``_s``, ``_N``, ``_m``); inputs
may carry units as strings. Model files are found by name from any folder.
"""

import math

import design

#: one set of fingers 3 and 4 of models/graspers/thesis_table_5_1.yaml per drum
GRASPER = {
    "spacing": 0.368, "sets": 1,
    "finger_models": {"lower": "models/fingers/thesis_nonuniform_hard.yaml"},
    "fingers": [
        {"name": "3", "group": "lower", "length": 0.076, "height": 0.032, "drum_radius": 0.108,
         "angle": "90 deg", "phi_x": "45 deg", "phi_y": "15 deg"},
        {"name": "4", "group": "lower", "length": 0.076, "height": 0.025, "drum_radius": 0.108,
         "angle": "112.5 deg", "phi_x": "90 deg", "phi_y": "7.5 deg"}]}

SCENE = {"kind": "grasp", "name": "quickstart", "grasper": GRASPER,
         "bird": "models/birds/mean_1_80kg.yaml", "conveyor": {"speed": "18 in/s"},
         "drum_speed": "20 rpm", "start": {"X": -0.075}, "duration": 0.5}

PROBLEM = {"kind": "design", "name": "quickstart_design", "scene": SCENE,
           "variables": {"groups.lower.stiffness_scale": [0.5, 2.0],
                         "fingers.4.angle": ["100.5 deg", "124.5 deg"]},
           "cap": "baseline", "model_check": "none",
           "solver": {"time_step": 0.01, "max_iter": 10, "outer_iterations": 1}}


def main() -> design.DesignResult:
    run = design.simulate(SCENE)
    print(run.verdict)
    series = run.timeseries
    print(f"{len(series['t_s'])} recorded instants; the bird's centre rose "
          f"{1e3 * (series['Z_m'].max() - series['Z_m'][0]):.1f} mm; finger 4 pressed up to "
          f"{series['F4_N'].max():.1f} N")
    result = design.solve(PROBLEM)
    print(result.verdict)
    d = result.design                                  # SI: the angle in rad
    print(f"optimum: the lower fingers' EI x {d['groups.lower.stiffness_scale']:.3f}, finger 4 "
          f"at {math.degrees(d['fingers.4.angle']):.1f} deg")
    return result


if __name__ == "__main__":
    main()
