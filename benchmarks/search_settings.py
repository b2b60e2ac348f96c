"""The main job's search: what its survey gains and what its budget costs.

``design solve problems/hold_time.yaml`` through the public API three
times, one after the other in this process, the problem otherwise as
shipped:

* as shipped: a survey of eight Sobol points, then the pattern search from
  the best of them, on a budget of 40 designs (the survey's included);
* the same search to its lattice optimum (the default budget, 150);
* no survey, to its lattice optimum: the search from the thesis's design
  alone, the baseline a user would otherwise have. Each row's wall time and
  verified hold are given as ratios to it.

The survey's size and the budget were chosen on this problem. So the
survey is also measured on others: the same problem for each other bird of
Table 5-5 (its scene's bird replaced, the cap its own baseline's peak, no
robustness scenes), as shipped against no survey on the same budget.

Prints two tables and writes benchmarks/results/search_settings.json.

    python -m benchmarks.search_settings
"""

from __future__ import annotations

import os
import tempfile
import time
from pathlib import Path

import design  # noqa: F401  first: it sets one BLAS thread before numpy loads (design/__init__.py)

import yaml

from benchmarks.results_file import machine, write_results
from design.api import solve
from design.solvers.optimize.pattern_search import MAX_SIMULATIONS

ROOT = Path(__file__).resolve().parents[1]
RESULTS = Path(__file__).parent / "results" / "search_settings.json"
PROBLEM = ROOT / "problems" / "hold_time.yaml"
#: each variant's name and its change to the problem's solver options
VARIANTS = {"as shipped": {},
            "to its lattice optimum": {"max_simulations": MAX_SIMULATIONS},
            "no survey, to its lattice optimum": {"survey": 0,
                                                  "max_simulations": MAX_SIMULATIONS}}
#: the variant the others are compared with
REFERENCE = "no survey, to its lattice optimum"
#: the other birds of Table 5-5, each run as shipped and with no survey
OTHER_BIRDS = ("small_1_20kg.yaml", "mean_1_66kg.yaml", "large_2_05kg.yaml")


def run(name: str, change: dict, bird: str | None = None) -> dict:
    """The main job with its solver options changed by ``change`` (and its
    scene's bird by ``bird``, a file of models/birds/, without the
    robustness scenes): its verified hold, design, simulations and wall
    time."""
    spec = yaml.safe_load(PROBLEM.read_text())
    spec["scene"] = str(PROBLEM.parent / spec["scene"])
    spec["solver"] = {**spec["solver"], **change}
    with tempfile.TemporaryDirectory() as out:
        if bird:
            scene = yaml.safe_load(Path(spec["scene"]).read_text())
            for key in ("grasper", "conveyor"):
                scene[key] = str(ROOT / scene[key])
            scene["bird"] = str(ROOT / "models" / "birds" / bird)
            spec["scene"] = str(Path(out) / "scene.yaml")
            Path(spec["scene"]).write_text(yaml.safe_dump(scene))
            spec["robustness"] = False
        t0 = time.perf_counter()
        result = solve(spec, out=str(Path(out) / "result")).to_dict()
        wall = time.perf_counter() - t0
    search = result["solver"]["search"]
    return {"variant": name, "bird": bird or "mean_1_80kg.yaml", "solver": spec["solver"],
            "status": result["status"],
            "wall_time_s": wall, "survey": search["survey"],
            "simulations": search["simulations"], "same_runs": search["same_runs"],
            "max_simulations": search["max_simulations"],
            "lattice_optimum": search["lattice_optimum"],
            "verified_hold_time_s": result["verification"]["hold_time_s"],
            "verified_max_finger_force_N": result["verification"]["max_finger_force_N"],
            "cap_N": result["verification"]["cap_N"],
            "baseline_hold_time_s": result["baseline"]["hold_time_s"],
            "robustness_beaten": (result.get("robustness") or {}).get("share_beaten"),
            "design": {v["name"]: v["optimum"] for v in result["variables"]}}


def main() -> None:
    load = os.getloadavg()
    rows = []
    for name, change in VARIANTS.items():
        rows.append(run(name, change))
        r = rows[-1]
        print(f"{name}: {r['status']}, verified hold {r['verified_hold_time_s']:.4f} s, "
              f"{r['simulations']} simulations, {r['wall_time_s']:.1f} s", flush=True)
    ref = next(r for r in rows if r["variant"] == REFERENCE)
    for r in rows:
        r["wall_over_reference"] = r["wall_time_s"] / ref["wall_time_s"]
        r["hold_over_reference"] = r["verified_hold_time_s"] / ref["verified_hold_time_s"]
        r["hold_over_baseline"] = r["verified_hold_time_s"] / r["baseline_hold_time_s"]
    print(f"\n{'variant':34s} {'sims':>4s} {'wall (s)':>8s} {'/ ref':>6s} "
          f"{'verified hold (s)':>17s} {'/ ref':>6s} {'/ baseline':>10s} {'peak (N)':>8s} "
          f"{'lattice optimum':>15s}")
    for r in rows:
        print(f"{r['variant']:34s} {r['simulations']:4d} {r['wall_time_s']:8.1f} "
              f"{r['wall_over_reference']:6.3f} {r['verified_hold_time_s']:17.5f} "
              f"{r['hold_over_reference']:6.3f} {r['hold_over_baseline']:10.3f} "
              f"{r['verified_max_finger_force_N']:8.2f} {str(r['lattice_optimum']):>15s}")
    print(f"(ref: {REFERENCE})")
    birds = []
    for bird in OTHER_BIRDS:
        shipped = run("as shipped", {}, bird)
        alone = run("no survey", {"survey": 0}, bird)
        birds.append({"bird": bird, "as_shipped": shipped, "no_survey": alone,
                      "hold_over_no_survey": shipped["verified_hold_time_s"]
                      / max(alone["verified_hold_time_s"], 1e-12)})
        print(f"{bird}: as shipped {shipped['status']} {shipped['verified_hold_time_s']:.4f} s "
              f"({shipped['wall_time_s']:.1f} s); no survey {alone['status']} "
              f"{alone['verified_hold_time_s']:.4f} s ({alone['wall_time_s']:.1f} s); baseline "
              f"{shipped['baseline_hold_time_s']:.4f} s", flush=True)
    write_results(RESULTS, {
        "machine": machine(load, at_end=True),
        "command": f"design solve {PROBLEM.relative_to(ROOT)} as shipped, with "
                   f"solver.max_simulations {MAX_SIMULATIONS}, and with solver.survey 0 and "
                   f"max_simulations {MAX_SIMULATIONS} (design.api.solve, one after the other)",
        "reference": REFERENCE, "rows": rows,
        "other_birds_command": "the same problem with its scene's bird replaced by each of "
                               f"{', '.join(OTHER_BIRDS)} (models/birds/), robustness off, "
                               "as shipped and with solver.survey 0",
        "other_birds": birds})


if __name__ == "__main__":
    main()
