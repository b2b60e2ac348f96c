"""Grasp integrators: speed against accuracy on one second of grasp.

The thesis's mean bird (Table 5-3) through the Table 5-1 grasper with hard
lower fingers, all 30 fingers (three sets of five per drum, the left
mirrored), from its start at X0 = -0.075 m for 1 s (set a grasps it; set b
arrives after it has left). Every integrator
and step is compared with a reference: the default adaptive integrator at
4x finer resolution (max step / 4, tolerances / 4^4). The thesis's baseline
is fixed-step BDF-4 with the forces frozen over each step: every row's wall
time is given as a ratio to it, at the thesis's 5.6 ms step and at 1.4 ms
(where it meets the accuracy targets), measured in the same run.

Warm against warm: a first run (the default integrator over the same
second) builds the contact solvers' CasADi functions and is reported apart
(``first_run``); every timed run comes after it. Each run's wall time is
split into setup (reach windows, finger models) and integration, and each
row records whether the run ended ok, with its message.

Prints a table and writes benchmarks/results/grasp.json.

    python benchmarks/grasp.py
"""

from __future__ import annotations

import os
from pathlib import Path

from benchmarks.results_file import machine, write_results
from design.reproduce.grasp import thesis_setup
from design.solvers.grasp.integrate import IntegratorSettings
from design.solvers.grasp.simulation import simulate_grasp
from design.tradeoff.grasp import CASES, DEFAULT

RESULTS = Path(__file__).parent / "results" / "grasp.json"
T_SKIP, DURATION = 0.0, 1.0
#: the thesis's integrator at its own step, and at the step where it meets
#: the accuracy targets (hold within 1 %, peak within 2 % of the reference)
BASELINES = ("bdf4 (thesis) 5.6 ms", "bdf4 1.4 ms")
#: the speed target for the default integrator: wall time per simulated second (s)
TARGET_WALL_PER_SIMULATED_S = 0.3


def measure(settings: IntegratorSettings, reach_filter: bool = True, t_skip: float = T_SKIP,
            duration: float = DURATION) -> dict:
    """design.tradeoff.grasp.simulate's fields, with the wall time split."""
    run = simulate_grasp(thesis_setup(t_skip, duration), settings, reach_filter=reach_filter)
    s = run.summary
    wall = run.setup_time + run.trajectory.wall_time
    return {"wall_s": wall, "setup_s": run.setup_time,
            "integration_s": run.trajectory.wall_time, "hold_time_s": s["hold_time_s"],
            "max_finger_force_N": s["max_finger_force_N"],
            "max_finger_force_finger": s["max_finger_force_finger"],
            "steps": run.trajectory.steps, "contact_solves": run.contact_solves,
            "skipped_finger_evaluations": run.skipped, "ok": run.trajectory.ok,
            "message": run.trajectory.message, "wall_per_simulated_s": wall / duration,
            "local_error_estimate_m": (s["local_error_estimate"] or {}).get("position_m")}


def _mm(metres: float | None) -> str:
    """A BDF-4 run's largest local error estimate in mm ('-': adaptive runs)."""
    return "-" if metres is None else f"{1e3 * metres:.3f}"


def first_run() -> dict:
    """The run that builds the CasADi functions (cold), setup and integration apart."""
    run = simulate_grasp(thesis_setup(T_SKIP, DURATION), DEFAULT)
    return {"integrator": "adaptive rk45 (default)", "setup_s": run.setup_time,
            "integration_s": run.trajectory.wall_time, "ok": run.trajectory.ok}


def main() -> None:
    load = [round(v, 2) for v in os.getloadavg()]
    cold = first_run()
    ref = measure(DEFAULT.finer(4))
    rows = []
    for name, settings in CASES.items():
        m = measure(settings)
        m["integrator"] = name
        m["hold_time_error_pct"] = 100 * (m["hold_time_s"] / ref["hold_time_s"] - 1)
        m["peak_force_error_pct"] = 100 * (m["max_finger_force_N"] / ref["max_finger_force_N"] - 1)
        rows.append(m)
    base = {name: next(r["wall_s"] for r in rows if r["integrator"] == name) for name in BASELINES}
    for r in rows:
        r["wall_over_baseline"] = {name: r["wall_s"] / wall for name, wall in base.items()}
    # the reach filter over a whole 2 s cycle (approach, grasp, release)
    filtered = measure(DEFAULT, True, 0.0, 2.0)
    unfiltered = measure(DEFAULT, False, 0.0, 2.0)
    default = rows[0]
    result = {
        "machine": machine(load),
        "scenario": "mean bird (Table 5-3), hard lower fingers, t = 0..1 s",
        "timing": "warm: every timed run follows first_run, which builds the CasADi "
                  "functions; wall_s = setup + integration",
        "first_run": cold, "baselines": list(BASELINES),
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
                    "target_wall_per_simulated_s": TARGET_WALL_PER_SIMULATED_S,
                    "met": default["wall_per_simulated_s"] <= TARGET_WALL_PER_SIMULATED_S,
                    "hold_time_error_pct": default["hold_time_error_pct"],
                    "peak_force_error_pct": default["peak_force_error_pct"]},
    }
    print(f"first run (cold, builds the CasADi functions): setup {cold['setup_s']:.2f} s, "
          f"integration {cold['integration_s']:.2f} s; every run below is warm")
    print(f"reference (4x finer): hold {ref['hold_time_s']:.5f} s, peak "
          f"{ref['max_finger_force_N']:.3f} N (finger {ref['max_finger_force_finger']}), "
          f"{ref['wall_s']:.1f} s wall{'' if ref['ok'] else ', NOT OK: ' + ref['message']}")
    print(f"{'integrator':32} {'wall/sim s':>10} {'x5.6ms':>7} {'x1.4ms':>7} {'steps':>6} "
          f"{'hold (s)':>9} {'err %':>7} {'peak (N)':>9} {'err %':>7} {'BDF est mm':>10}")
    for r in rows:
        ratio = r["wall_over_baseline"]
        print(f"{r['integrator']:32} {r['wall_per_simulated_s']:10.2f} "
              f"{ratio[BASELINES[0]]:7.2f} {ratio[BASELINES[1]]:7.2f} {r['steps']:6d} "
              f"{r['hold_time_s']:9.5f} {r['hold_time_error_pct']:+7.2f} "
              f"{r['max_finger_force_N']:9.3f} {r['peak_force_error_pct']:+7.2f} "
              f"{_mm(r['local_error_estimate_m']):>10}"
              f"{'' if r['ok'] else '  <- not ok: ' + r['message']}")
    print("x5.6ms, x1.4ms: wall time over the thesis's BDF-4 (frozen forces) at its 5.6 ms step "
          "and at 1.4 ms, where it meets the 1 % / 2 % targets; BDF est: the largest estimated "
          "local error of a BDF-4 step in the bird's position")
    print(f"default integrator: {default['wall_per_simulated_s']:.2f} s per simulated second "
          f"against the {TARGET_WALL_PER_SIMULATED_S} s target: "
          f"{'met' if result['targets']['met'] else 'NOT met'} (load average {load[0]} at start)")
    rf = result["reach_filter"]
    print(f"reach filter (2 s cycle): {rf['with_s']:.2f} s with, {rf['without_s']:.2f} s without "
          f"({rf['saved_pct']:.0f}% saved; {rf['contact_solves_with']} against "
          f"{rf['contact_solves_without']} contact solves)")
    write_results(RESULTS, result)


if __name__ == "__main__":
    main()
