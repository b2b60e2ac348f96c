"""Two candidate explanations of Figures 5-17/5-18: run
from the repository root,
``.venv/bin/python examples/validation/football_variants.py [--out DIR]``.

1. ``stiff``: every finger 10x and 100x stiffer about its stiff axis and in
   twist (towards the thesis's assumption 2, fingers rigid out of their
   plane), spatial model, the football studies of Figure 5-18 (finger 3 at
   φx = 45°, 60°, 70°) and the experiment.
2. ``thesis integrator``: the thesis's own model (``planar-thesis``) with its
   integrator, BDF-4 with forces frozen over each step and no error check,
   at Table 5-4's 16.6 ms on the football scenes and Table 5-3's 5.6 ms on
   the arriving mean bird.

Printed as a table and written to ``DIR/football_variants.json`` (default
reports/validation_variants/). About 14 minutes on one core (the 10x stiff rod runs
the longest).
"""

from __future__ import annotations

import sys
import time
from dataclasses import replace

from design.reproduce.grasp import (FOOTBALL_START, SIZES_START, contact_nodes, football_setup,
                                    mean_bird_setup)
from design.reproduce.grasp_rows import (DENSE, back_off, family_peaks, impulse_share, passes,
                                         touching, x_end, x_impulse)
from design.solvers.grasp.integrate import IntegratorSettings
from design.solvers.grasp.simulation import GraspSetup, simulate_grasp
from design.tradeoff.grasp import CASES as TRADEOFF_CASES
from study_output import parser as study_parser, write_rows

#: wall time allowed per run (s): each takes 2-120 s
BUDGET = 300.0
FOOTBALL_SCENES = {"experiment": (FOOTBALL_START, 1.16, 60.0),
                   "finger µ 0": (SIZES_START, 0.0, 60.0),
                   "finger µ 0.4": (SIZES_START, 0.4, 60.0),
                   "φx 45": (SIZES_START, 1.16, 45.0),
                   "φx 60": (SIZES_START, 1.16, 60.0),
                   "φx 70": (SIZES_START, 1.16, 70.0)}


def stiffened(setup: GraspSetup, factor: float) -> GraspSetup:
    """Every finger ``factor`` times stiffer out of its plane and in twist."""
    fingers = tuple(replace(gf, finger=replace(
        gf.finger, stiff=gf.finger.stiffness_out.scaled(factor),
        torsion=gf.finger.torsion_rigidity.scaled(factor))) for gf in setup.grasper.fingers)
    return replace(setup, grasper=replace(setup.grasper, fingers=fingers))


def cases():
    """(variant, scene, setup, integrator settings), in the order run."""
    adaptive = IntegratorSettings(max_wall_time=BUDGET)
    for factor in (10.0, 100.0):
        for scene in ("experiment", "φx 45", "φx 60", "φx 70"):
            yield (f"stiff x{factor:g}", scene, stiffened(football_setup(
                *FOOTBALL_SCENES[scene]), factor), adaptive)
    for scene, args in FOOTBALL_SCENES.items():
        yield ("thesis integrator", scene, football_setup(*args, model="planar-thesis"),
               replace(TRADEOFF_CASES["bdf4 (thesis) 16.6 ms"], max_wall_time=BUDGET))
    for lower in ("soft", "hard", "constant"):
        yield ("thesis integrator", f"mean bird, {lower}", mean_bird_setup(lower, "planar-thesis"),
               replace(TRADEOFF_CASES["bdf4 (thesis) 5.6 ms"], max_wall_time=BUDGET))


def main(argv: list[str] | None = None) -> int:
    parser = study_parser(__doc__, "validation_variants")
    args = parser.parse_args(argv)
    rows, start = [], time.perf_counter()
    for variant, scene, setup, settings in cases():
        run = simulate_grasp(setup, settings, contact_nodes(setup))
        peaks = family_peaks(run)
        r = {"variant": variant, "scene": scene, "ok": bool(run.trajectory.ok),
             "message": run.summary["message"], "centre_rise_m": run.summary["centre_rise_m"],
             "passes": passes(run), "back_off_m": back_off(run), "x_end_m": x_end(run),
             "peak_finger": max(peaks, key=peaks.get) if peaks else None,
             "peak_force_N": max(peaks.values(), default=0.0), "finger_peaks_N": peaks,
             "fingers_touching": touching(run),
             "finger_3_x_impulse_Ns": x_impulse(run, "3"), "x_impulse_Ns": x_impulse(run, None),
             "share_within_1_5_in": impulse_share(run, lambda rec: abs(rec.y[0]) <= DENSE)}
        rows.append(r)
        print(f"{variant:18s} {scene:20s} {'ok' if r['ok'] else 'FAILED':6s} rise "
              f"{1e3 * r['centre_rise_m']:9.1f} mm  {'passes' if r['passes'] else 'no pass'}  "
              f"back {1e3 * r['back_off_m']:10.1f} mm  peak {r['peak_finger']} "
              f"{r['peak_force_N']:5.1f} N  finger 3 X impulse {r['finger_3_x_impulse_Ns']:+.3f} "
              f"N s  fingers {r['fingers_touching']}"
              + ("" if r["ok"] else f"  ({r['message']})"), flush=True)
    write_rows(args.out / "football_variants.json", rows, time.perf_counter() - start)
    return 0


if __name__ == "__main__":
    sys.exit(main())
