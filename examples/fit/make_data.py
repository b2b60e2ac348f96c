"""Make the example data sets of examples/fit/ (run from the repository root:
``.venv/bin/python examples/fit/make_data.py``; it rewrites the two CSVs).

* ``bench_finger.csv``: a bench test of the thesis's hard rubber finger
  (models/fingers/thesis_nonuniform_hard.yaml) simulated by the toolkit's
  collocation elastica (its error estimate is below 1e-9 m), read as a camera
  would read markers: deflection y at every 10 mm and the slope at the load
  point, with Gaussian noise of 0.2 mm and 0.5 deg, rounded to 0.01 mm and
  0.01 deg.
* ``figure_5_10_belt.csv``: Figure 5-10's belt, built from the thesis's
  stated values only (the figure's image is not available): 18 in/s
  (0.457 m/s) slowing to 10 in/s (0.254 m/s), time axis 1.4-2.8 s, the
  slow-down 0.4 s into the one-second cycle that starts at the axis's
  1.4 s, i.e. at 1.8 s; the ramp at 2 m/s² (the rate models/conveyors/
  decelerate_figure_5_10.yaml assumes: the thesis gives none); sampled at
  100 Hz with Gaussian noise of 0.005 m/s (an encoder's speed from counts),
  rounded to 0.1 mm/s.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from design.calibration.data import FingerData, Observation
from design.calibration.elastica import elastica_predictions
from design.io.fingers import read_finger
from design.physics.beam import PointLoad
from design.physics.bird import belt_motion
from design.reproduce.grasp import load_model

HERE = Path(__file__).resolve().parent
FINGER_SEED, BELT_SEED = 2033, 510
#: (load point m, loads N): three weights hung at each of four points
BENCH = ((0.0508, (2.0, 4.0, 8.0)), (0.1016, (1.0, 2.0, 4.0)), (0.1524, (0.5, 1.0, 2.0)),
         (0.1905, (0.3, 0.6, 1.2)))
MARKERS = np.round(np.arange(0.01, 0.2001, 0.01), 4)
SIGMA_Y, SIGMA_PSI = 0.2e-3, np.radians(0.5)


def bench_finger() -> str:
    finger = load_model(read_finger, "fingers", "thesis_nonuniform_hard.yaml")
    loads = tuple(PointLoad(F, np.pi / 2, at) for at, forces in BENCH for F in forces)
    obs = [Observation(k, float(s), "y", 0.0, SIGMA_Y, 0)
           for k in range(len(loads)) for s in MARKERS]
    obs += [Observation(k, ld.at, "psi", 0.0, SIGMA_PSI, 0) for k, ld in enumerate(loads)]
    exact, sols = elastica_predictions(finger, FingerData(loads, tuple(obs)), nodes=64)
    assert all(s.converged and s.error_estimate < 1e-9 for s in sols)
    rng = np.random.default_rng(FINGER_SEED)
    noisy = exact + rng.standard_normal(exact.size) * np.array([o.sigma for o in obs])
    lines = [
        "# Bench test of a finger (example data for `design fit`, examples/fit/finger_bench.yaml).",
        "# Synthetic: the thesis's hard finger (models/fingers/thesis_nonuniform_hard.yaml,",
        "# EI(s) = 9.07 MPa x eq. 2.33) under weights hung perpendicular to it, solved by the",
        "# toolkit's collocation elastica (64 intervals, error < 1e-9 m); markers every 10 mm",
        "# read for y with noise 0.2 mm, the slope at the load point with noise 0.5 deg",
        f"# (Gaussian, numpy default_rng seed {FINGER_SEED}); rounded to 0.01 mm and 0.01 deg.",
        "# Made by examples/fit/make_data.py. alpha = 90 deg: a push towards +y.",
        "F [N],alpha [deg],at [mm],s [mm],y [mm],psi [deg]"]
    for o, value in zip(obs, noisy):
        ld = loads[o.case]
        y = f"{value * 1e3:.2f}" if o.quantity == "y" else ""
        psi = f"{np.degrees(value):.2f}" if o.quantity == "psi" else ""
        lines.append(f"{ld.force:g},90,{ld.at * 1e3:.1f},{o.s * 1e3:.1f},{y},{psi}")
    return "\n".join(lines) + "\n"


def figure_5_10_belt() -> str:
    t = np.round(np.arange(1.4, 2.8 + 1e-9, 0.01), 2)
    v = np.array([float(belt_motion(ti, 0.457, 0.254, 2.0, 1.8)[0]) for ti in t])
    rng = np.random.default_rng(BELT_SEED)
    v = v + 0.005 * rng.standard_normal(t.size)
    lines = [
        "# Figure 5-10's belt speed, for `design fit` (examples/fit/belt_figure_5_10.yaml).",
        "# CONSTRUCTED from the thesis's stated values, not digitised from the figure (its image",
        "# is not available): 18 in/s (0.457 m/s) slowing to 10 in/s (0.254 m/s); time axis",
        "# 1.4-2.8 s; the slow-down 0.4 s into the one-second cycle, taken to start at the",
        "# axis's 1.4 s, so at t = 1.8 s (the text's other statement, X = -0.142 m for a ball",
        "# from X0 = -0.305 m at 0.457 m/s, is 0.357 s in: the two agree within 0.05 s).",
        "# Ramp: 2 m/s^2, the rate models/conveyors/decelerate_figure_5_10.yaml assumes (the",
        "# thesis gives none), so 1.8 to 1.9015 s. Sampled at 100 Hz; noise Gaussian 0.005 m/s",
        f"# (numpy default_rng seed {BELT_SEED}); rounded to 0.1 mm/s. Made by",
        "# examples/fit/make_data.py.",
        "t [s],v [m/s]"]
    lines += [f"{ti:.2f},{vi:.4f}" for ti, vi in zip(t, v)]
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    (HERE / "bench_finger.csv").write_text(bench_finger(), encoding="utf-8")
    (HERE / "figure_5_10_belt.csv").write_text(figure_5_10_belt(), encoding="utf-8")
