"""Grasp integrators: speed against accuracy on one second of grasp.

The thesis's mean bird (Table 5-3) through the Table 5-1 grasper with hard
lower fingers, all 30 fingers (three sets of five per drum, the left
mirrored), from its start at X0 = -0.075 m for 1 s (set a grasps it; set b
arrives after it has left). Every integrator
and step is compared with a reference: the default adaptive integrator at
4x finer resolution (max step / 4, tolerances / 4^4). The thesis's baseline
is fixed-step BDF-4 with the forces frozen over each step.

Prints a table and writes benchmarks/results/grasp.json.

    python benchmarks/grasp.py
"""

from __future__ import annotations

import json
import os
import platform
from pathlib import Path

from design.io.results import jsonable
from design.reproduce.grasp import thesis_setup
from design.solve.grasp.integrate import IntegratorSettings
from design.tradeoff.grasp import CASES, DEFAULT, simulate

RESULTS = Path(__file__).parent / "results" / "grasp.json"
T_SKIP, DURATION = 0.0, 1.0


def measure(settings: IntegratorSettings, reach_filter: bool = True, t_skip: float = T_SKIP,
            duration: float = DURATION) -> dict:
    m = simulate(thesis_setup(t_skip, duration), settings, reach_filter=reach_filter)
    return {**m, "wall_per_simulated_s": m["wall_s"] / duration}


def main() -> None:
    ref = measure(DEFAULT.finer(4))
    rows = []
    for name, settings in CASES.items():
        m = measure(settings)
        m["integrator"] = name
        m["hold_time_error_pct"] = 100 * (m["hold_time_s"] / ref["hold_time_s"] - 1)
        m["peak_force_error_pct"] = 100 * (m["max_finger_force_N"] / ref["max_finger_force_N"] - 1)
        rows.append(m)
    # the reach filter over a whole 2 s cycle (approach, grasp, release)
    filtered = measure(DEFAULT, True, 0.0, 2.0)
    unfiltered = measure(DEFAULT, False, 0.0, 2.0)
    default = rows[0]
    result = {
        "machine": {"python": platform.python_version(), "cores": os.cpu_count()},
        "scenario": "mean bird (Table 5-3), hard lower fingers, t = 0..1 s",
        "reference": {"integrator": "adaptive rk45, 4x finer", **ref},
        "rows": rows,
        "reach_filter": {"scenario": "t = 0..2 s", "with_s": filtered["wall_s"],
                         "without_s": unfiltered["wall_s"],
                         "saved_pct": 100 * (1 - filtered["wall_s"] / unfiltered["wall_s"]),
                         "skipped_finger_evaluations": filtered["skipped_finger_evaluations"],
                         "contact_solves_with": filtered["contact_solves"],
                         "contact_solves_without": unfiltered["contact_solves"],
                         "same_hold_time": filtered["hold_time_s"] == unfiltered["hold_time_s"]},
        "targets": {"wall_per_simulated_s": default["wall_per_simulated_s"],
                    "target_wall_per_simulated_s": 5.0,
                    "hold_time_error_pct": default["hold_time_error_pct"],
                    "peak_force_error_pct": default["peak_force_error_pct"]},
    }
    print(f"reference (4x finer): hold {ref['hold_time_s']:.5f} s, peak "
          f"{ref['max_finger_force_N']:.3f} N (finger {ref['max_finger_force_finger']}), "
          f"{ref['wall_s']:.1f} s wall")
    print(f"{'integrator':32} {'wall/sim s':>10} {'steps':>6} {'hold (s)':>9} {'err %':>7} "
          f"{'peak (N)':>9} {'err %':>7}")
    for r in rows:
        print(f"{r['integrator']:32} {r['wall_per_simulated_s']:10.2f} {r['steps']:6d} "
              f"{r['hold_time_s']:9.5f} {r['hold_time_error_pct']:+7.2f} "
              f"{r['max_finger_force_N']:9.3f} {r['peak_force_error_pct']:+7.2f}")
    rf = result["reach_filter"]
    print(f"reach filter (2 s cycle): {rf['with_s']:.2f} s with, {rf['without_s']:.2f} s without "
          f"({rf['saved_pct']:.0f}% saved; {rf['contact_solves_with']} against "
          f"{rf['contact_solves_without']} contact solves)")
    RESULTS.parent.mkdir(parents=True, exist_ok=True)
    RESULTS.write_text(json.dumps(jsonable(result), indent=1) + "\n")
    print(f"wrote {RESULTS}")


if __name__ == "__main__":
    main()
