"""Running a fit problem: a finger's EI(s) or a belt's speed profile from
measurements, written as a model file that scenes reference as they are."""

from __future__ import annotations


import numpy as np
import yaml

from design import __version__
from design.calibration import belt as belt_fit
from design.calibration.convex import SOLVER
from design.io.fit_problem import BeltFitProblem
from design.io.grasp_scene import read_conveyor
from design.io.reader import Reader
from design.run import Progress, RunOutput
from design.run.finger_fit import run_finger


def run(problem, progress: Progress | None = None) -> RunOutput:
    if isinstance(problem, BeltFitProblem):
        return run_belt(problem, progress)
    return run_finger(problem, progress)


# ------------------------------------------------------------------- belt

def conveyor_yaml(problem: BeltFitProblem, fit: belt_fit.RampFit) -> str:
    """The conveyor model file (SI): constant speed, or the fitted slow-down
    starting at ``start_time`` on the simulation's clock."""
    spec = {"kind": "conveyor", "name": problem.name,
            "description": f"Fitted by design fit from {problem.data_file.name}.",
            "source": f"design fit ({problem.data_file.name})", "speed": fit.v0}
    if fit.decelerates:
        spec.update({"final_speed": fit.v1, "rate": fit.rate,
                     "start_time": max(fit.t_start - problem.time_zero, 0.0)})
    header = (f"# Written by `design fit` ({problem.name}) from {problem.data_file.name}: "
              f"the log's t = {problem.time_zero:g} s is the simulation's t = 0.\n")
    return header + yaml.safe_dump({k: (float(v) if isinstance(v, (float, np.floating)) else v)
                                    for k, v in spec.items()}, sort_keys=False, width=100)


def run_belt(problem: BeltFitProblem, progress: Progress | None = None) -> RunOutput:
    """Fit the monotone profile and the conveyor model; write the conveyor file."""
    t, v = problem.t, problem.v
    if progress:
        progress(f"belt fit: {t.size} samples")
    mono = belt_fit.monotone_fit(t, v, problem.knots)
    ramp = belt_fit.ramp_fit(t, v)
    warnings, ok = [], True
    if ramp.decelerates and ramp.t_start < problem.time_zero - 1e-9:
        ok = False
        warnings.append(f"the slow-down starts at t = {ramp.t_start:.4g} s in the log, before "
                        f"belt.time_zero = {problem.time_zero:g} s: a conveyor model cannot "
                        f"start it before the simulation does (start_time written as 0)")
    if ramp.rms > 1.5 * mono.rms:
        warnings.append(f"the constant-ramp-constant model leaves {ramp.rms:.3g} m/s RMS "
                        f"against the monotone fit's {mono.rms:.3g} m/s: the belt does not slow "
                        f"as one constant-rate ramp")
    text = conveyor_yaml(problem, ramp)
    check = Reader("conveyor.yaml")
    conveyor = read_conveyor(check, yaml.safe_load(text), "", problem.data_file.parent)
    if not check.ok:
        ok = False
        warnings.append("the conveyor file does not read back: "
                        + "; ".join(str(p) for p in check.problems))
    fitted = {"speed": ramp.v0, "final_speed": ramp.v1 if ramp.decelerates else None,
              "rate": ramp.rate if ramp.decelerates else None,
              "start_time": (ramp.t_start - problem.time_zero) if ramp.decelerates else None,
              "end_time": (ramp.t_end - problem.time_zero) if ramp.decelerates else None}
    se = {"speed": ramp.se["v0"], "final_speed": ramp.se["v1"], "start_time": ramp.se["t_start"],
          "end_time": ramp.se["t_end"], "rate": ramp.se["rate"]}
    comparison = [{"quantity": k, "fitted": fitted.get(k), "standard_error": se.get(k),
                   "stated": val, "difference": (fitted.get(k) - val)
                   if fitted.get(k) is not None and val is not None else None}
                  for k, val in problem.reference.items()]
    result = {
        "kind": "fit", "target": "belt", "name": problem.name, "toolkit_version": __version__,
        "units": {"time": "s", "speed": "m/s", "acceleration": "m/s^2"},
        "data_file": str(problem.data_file), "samples": int(t.size),
        "time_zero": problem.time_zero, "decelerates": ramp.decelerates,
        "fitted": fitted, "standard_errors": se,
        "ramp": {"rms": ramp.rms, "t_start_log": ramp.t_start, "t_end_log": ramp.t_end,
                 "solve_time_s": ramp.solve_time_s},
        "monotone": {"solver": f"{SOLVER} via cvxpy", "knots": problem.knots, "rms": mono.rms,
                     "status": mono.status, "solve_time_s": mono.solve_time_s,
                     "knot_times": mono.knots, "knot_speeds": mono.speeds},
        "comparison": comparison, "warnings": warnings,
        "model": {"file": "conveyor.yaml",
                  "conveyor": None if conveyor is None else conveyor.describe()},
        "ok": ok,
    }
    rows = [{"t_s": ti, "v_m_s": vi, "ramp_m_s": r, "monotone_m_s": m, "residual_m_s": r - vi}
            for ti, vi, r, m in zip(t, v, ramp.predictions, mono.predictions)]
    return RunOutput(result, {"samples.csv": rows}, ok=ok, files={"conveyor.yaml": text},
                     artifacts={"problem": problem, "ramp": ramp, "monotone": mono})
