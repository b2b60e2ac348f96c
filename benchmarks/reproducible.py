"""Does a design problem give the same answer on every machine?

Runs ``design solve PROBLEM`` (default problems/hold_time.yaml) in fresh
processes under the variations a user's machine may bring: the same run
again, compiled functions off (``DESIGN_COMPILE=0``), two BLAS threads
(``OPENBLAS_NUM_THREADS=2``), another CPU's BLAS kernels
(``OPENBLAS_CORETYPE=Prescott``), and the baseline design perturbed by 1e-9
relative (finger 4's angle, through the scene's ``mounts``). Each run's
design variables (scaled to their boxes) and verified hold are compared
with the first run's: they should agree within 1e-3 and 1 ms. Prints a table
and writes benchmarks/results/reproducible.json.

    python -m benchmarks.reproducible [PROBLEM] [--workers 2] [--keep DIR] [--only LABEL ...]
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import yaml

from benchmarks.results_file import write_results
from design.io.files import resolve

ROOT = Path(__file__).resolve().parents[1]
#: (label, environment changes, perturb the baseline)
VARIATIONS = (("reference", {}, False), ("the same again", {}, False),
              ("DESIGN_COMPILE=0", {"DESIGN_COMPILE": "0"}, False),
              ("OPENBLAS_NUM_THREADS=2", {"OPENBLAS_NUM_THREADS": "2"}, False),
              ("OPENBLAS_CORETYPE=Prescott", {"OPENBLAS_CORETYPE": "Prescott"}, False),
              ("baseline perturbed 1e-9", {}, True))
#: the agreement asked for: scaled design variables, verified hold (s)
DESIGN_TOLERANCE, HOLD_TOLERANCE = 1e-3, 1e-3


def perturbed(problem: Path, folder: Path) -> Path:
    """The problem with its scene's finger 4 turned by 1e-9 of its angle."""
    data = yaml.safe_load(problem.read_text())
    scene_path = resolve(data["scene"], problem.parent)
    scene = yaml.safe_load(scene_path.read_text())

    def found(reference: str) -> str:               # as the toolkit finds a model file
        return str(resolve(reference, scene_path.parent))

    grasper = yaml.safe_load(Path(found(scene["grasper"])).read_text())
    angle = next(f["angle"] for f in grasper["fingers"] if str(f["name"]) == "4")
    degrees = float(str(angle).split()[0])
    for key in ("grasper", "bird", "conveyor"):
        scene[key] = found(scene[key])
    if "finger_models" in scene:
        scene["finger_models"] = {g: found(f) for g, f in scene["finger_models"].items()}
    scene["mounts"] = {"4": {"angle": f"{degrees * (1 + 1e-9)!r} deg"}}
    data["scene"] = scene
    out = folder / problem.name
    out.write_text(yaml.safe_dump(data, sort_keys=False))  # the variables' order kept
    return out


def run(problem: Path, label: str, changes: dict, folder: Path) -> dict:
    out = folder / label.replace(" ", "_").replace("=", "_")
    env = {**os.environ, **changes}
    t0 = time.perf_counter()
    done = subprocess.run([sys.executable, "-m", "design", "solve", str(problem), "--out",
                           str(out), "--quiet"], env=env, capture_output=True, text=True,
                          cwd=ROOT)
    wall = time.perf_counter() - t0
    result = json.loads((out / "result.json").read_text()) if (out / "result.json").exists() \
        else {}
    return {"label": label, "exit": done.returncode, "wall_time_s": wall,
            "status": result.get("status"), "variables": result.get("variables", []),
            "hold_time_s": result.get("verification", {}).get("hold_time_s"),
            "numerics": result.get("numerics"), "stderr": done.stderr[-2000:],
            "trials": trials(result)}


def trials(result: dict) -> list[list[float]]:
    """The design loop's simulated hold (s) and peak (N) of every design it
    tried, followed by the design (scaled)."""
    return [[h["simulated_hold_time_s"], h["simulated_peak_force_N"], *h["candidate_scaled"]]
            for h in result.get("solver", {}).get("history", [])
            if "simulated_hold_time_s" in h]


def round_off(r: dict, reference: dict) -> dict:
    """How far the loop's simulations moved under a variation: the largest
    differences of the tried designs' holds and peaks where both runs tried
    the same designs (within 1e-6, scaled) in the same order; None where
    they did not."""
    a, b = r.get("trials") or [], reference.get("trials") or []
    same = bool(a) and len(a) == len(b) and all(
        len(u) == len(v) and max(abs(x - y) for x, y in zip(u[2:], v[2:])) <= 1e-6
        for u, v in zip(a, b))
    return {"largest_trial_hold_difference_s":
            max(abs(u[0] - v[0]) for u, v in zip(a, b)) if same else None,
            "largest_trial_peak_difference_N":
            max(abs(u[1] - v[1]) for u, v in zip(a, b)) if same else None}


def scaled(variables: list[dict]) -> dict[str, float]:
    """Each variable's optimum scaled to its box, by name."""
    return {v["name"]: (v["optimum"] - v["lower"]) / (v["upper"] - v["lower"])
            for v in variables}


def difference(variables: list[dict], reference: list[dict]) -> float:
    """The largest scaled difference of two designs, variable by variable."""
    a, b = scaled(variables), scaled(reference)
    if a.keys() != b.keys():
        raise ValueError(f"the runs design different variables: {sorted(a)} and {sorted(b)}")
    return max(abs(a[name] - b[name]) for name in a)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("problem", nargs="?", default=str(ROOT / "problems" / "hold_time.yaml"))
    parser.add_argument("--workers", type=int, default=1)
    parser.add_argument("--keep", type=Path, help="keep every run's output folder here")
    parser.add_argument("--only", nargs="+", choices=[v[0] for v in VARIATIONS[1:]],
                        help="run these variations (and the reference) only")
    args = parser.parse_args()
    problem = Path(args.problem).resolve()
    chosen = [v for v in VARIATIONS if v is VARIATIONS[0] or args.only is None or
              v[0] in args.only]
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp) if args.keep is None else args.keep.resolve()
        folder.mkdir(parents=True, exist_ok=True)
        jobs = [(perturbed(problem, folder) if perturb else problem, label, changes)
                for label, changes, perturb in chosen]
        with ThreadPoolExecutor(args.workers) as pool:
            runs = list(pool.map(lambda job: run(*job, folder), jobs))
    reference = runs[0]
    rows = []
    for r in runs:
        ok = r["exit"] in (0, 1) and r["variables"] and reference["variables"]
        design = difference(r["variables"], reference["variables"]) if ok else None
        hold = abs(r["hold_time_s"] - reference["hold_time_s"]) if ok else None
        rows.append({"variation": r["label"], "status": r["status"],
                     "wall_time_s": round(r["wall_time_s"], 1),
                     "verified_hold_s": r["hold_time_s"], "design_difference": design,
                     "hold_difference_s": hold, **round_off(r, reference),
                     "agrees": bool(ok and design <= DESIGN_TOLERANCE
                                    and hold <= HOLD_TOLERANCE)})
    print(f"{'variation':<28} {'status':<22} {'wall (s)':>9} {'hold (s)':>9} "
          f"{'|Δd| scaled':>12} {'|Δhold| (s)':>12} agrees")
    for row in rows:
        d, h = row["design_difference"], row["hold_difference_s"]
        print(f"{row['variation']:<28} {str(row['status']):<22} {row['wall_time_s']:>9.1f} "
              f"{row['verified_hold_s'] or float('nan'):>9.4f} "
              f"{'-' if d is None else f'{d:.2e}':>12} {'-' if h is None else f'{h:.2e}':>12} "
              f"{row['agrees']}")
    write_results(ROOT / "benchmarks" / "results" / "reproducible.json", {
        "problem": str(problem.relative_to(ROOT)) if problem.is_relative_to(ROOT) else
        str(problem), "tolerances": {"design_scaled": DESIGN_TOLERANCE,
                                     "hold_s": HOLD_TOLERANCE},
        "rows": rows, "runs": [{k: v for k, v in r.items() if k != "trials"} for r in runs],
        "date": time.strftime("%Y-%m-%d"),
        "commit": subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT,
                                 capture_output=True, text=True).stdout.strip(),
        "machine": {"cpus": os.cpu_count()}})


if __name__ == "__main__":
    main()
