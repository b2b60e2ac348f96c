"""Running a fit problem: a finger's EI(s) or a belt's speed profile from
measurements, written as a model file that scenes reference as they are."""

from __future__ import annotations

import time

import numpy as np
import yaml

from design import __version__
from design.fit import belt as belt_fit
from design.fit.convex import BAND_Z, FLAG_LIMIT, SOLVER, ProfileFit, fit_compliance
from design.fit.data import FingerData
from design.fit.elastica import elastica_predictions, refine
from design.fit.exponential import project
from design.fit.kernel import KnotCompliance, kernel
from design.io.fit_problem import BeltFitProblem, FingerFitProblem
from design.io.fingers import read_finger
from design.io.grasp_scene import read_conveyor
from design.io.reader import Reader
from design.physics.beam import Finger
from design.physics.stiffness import Stiffness, TableI
from design.run import Progress, RunOutput

#: the elastica refines the fit when it differs from the linear model by more
#: than this many standard deviations of the stated noise at some measurement
NONLINEAR_LIMIT = 1.0
#: EI counts as determined where its 95 % band is narrower than ± this fraction
DETERMINED_BAND = 0.25
#: a fitted compliance below this fraction of the profile's median is raised
#: to it in the model file (EI at most 100x the median, never infinite)
COMPLIANCE_FLOOR = 1e-2
SOLVER_WHY = ("Clarabel (interior point, through cvxpy): solves the QP's quadratic objective "
              "directly to ~1e-8 relative accuracy, enough to compare the residuals of "
              "neighbouring weights; OSQP (first-order ADMM) stops at 1e-5 tolerances and "
              "converges slowly past them")


def run(problem, progress: Progress | None = None) -> RunOutput:
    if isinstance(problem, BeltFitProblem):
        return run_belt(problem, progress)
    return run_finger(problem, progress)


# ----------------------------------------------------------------- finger

def linear_predictions(fit: ProfileFit, data: FingerData) -> np.ndarray:
    """Every observation's small-deflection value (x: the point's s)."""
    K, used = kernel(fit.knots, data)
    out = np.array([o.s for o in data.observations])
    out[used] = K @ fit.c
    return out


def safe_profile(knots: np.ndarray, c: np.ndarray) -> tuple[KnotCompliance, bool]:
    """The profile with its compliance raised to :data:`COMPLIANCE_FLOOR` x
    the median where it is lower (EI finite); whether any was raised."""
    floor = COMPLIANCE_FLOOR * float(np.median(c))
    return KnotCompliance(tuple(knots), tuple(np.maximum(c, floor))), bool(np.any(c < floor))


def model_predictions(stiffness: Stiffness, length: float, data: FingerData, method: str
                      ) -> np.ndarray:
    """The observations as a finger of this stiffness predicts them, by the
    fit's method (the small-deflection kernel on a fine grid, or the elastica)."""
    if method == "elastica":
        return elastica_predictions(Finger(length, stiffness), data)[0]
    fine = np.linspace(0.0, length, 401)
    K, used = kernel(fine, data)
    out = np.array([o.s for o in data.observations])
    out[used] = K @ (1.0 / stiffness.ei(fine))
    return out


def finger_yaml(problem: FingerFitProblem, stiffness: Stiffness, E: float, header: str) -> str:
    """The finger model file: a cubic-spline table of I(s) = EI(s) / E, or the
    exponential family (SI)."""
    d = stiffness.describe()
    if d["type"] == "table":
        profile = {"type": "table", "s": [float(v) for v in d["s"]],
                   "I": [float(v) for v in d["I"]]}
    else:
        profile = {"type": "exponential", **{k: float(d[k]) for k in ("A", "B", "C", "a", "b")}}
    spec = {"kind": "finger", "name": problem.name,
            "description": f"Fitted by design fit from {problem.data_file.name}.",
            "source": f"design fit ({problem.data_file.name})",
            "length": float(problem.length), "E": float(E), "I": profile}
    body = yaml.safe_dump(spec, sort_keys=False, default_flow_style=None, width=100)
    return "".join(f"# {line}\n" for line in header.splitlines()) + body


def _ranges(s: np.ndarray, mask: np.ndarray) -> list[tuple[float, float]]:
    """Contiguous runs of True in mask, as (first s, last s)."""
    out, start = [], None
    for i, m in enumerate(mask):
        if m and start is None:
            start = i
        if (not m or i == mask.size - 1) and start is not None:
            end = i if m else i - 1
            out.append((float(s[start]), float(s[end])))
            start = None
    return out


def choose_method(problem: FingerFitProblem, convex: ProfileFit, progress) -> dict:
    """Whether the small-deflection fit is enough: the elastica through its
    profile against the linear model, in standard deviations of the noise."""
    data, asked = problem.data, problem.settings.method
    if asked == "small-deflection":
        return {"method": "small-deflection", "reason": "asked for (fit.method)",
                "nonlinearity": None, "start": None}
    if progress:
        progress("checking the linear model against the elastica")
    stiff, _ = safe_profile(convex.knots, convex.c)
    el, sols = elastica_predictions(Finger(problem.length, stiff), data)
    lin = linear_predictions(convex, data)
    gap = float(np.max(np.abs(el - lin) / data.sigmas))
    slope = float(max(np.max(np.abs(s.psi)) for s in sols))
    if asked == "elastica":
        return {"method": "elastica", "reason": "asked for (fit.method)", "nonlinearity": gap,
                "start": sols, "max_slope": slope}
    if gap > NONLINEAR_LIMIT:
        reason = (f"the elastica through the small-deflection fit differs from the linear "
                  f"model by up to {gap:.3g} standard deviations of the noise (limit "
                  f"{NONLINEAR_LIMIT:g}; slopes up to {slope:.3g} rad): refined on the elastica")
        return {"method": "elastica", "reason": reason, "nonlinearity": gap, "start": sols,
                "max_slope": slope}
    reason = (f"the elastica through the fit differs from the linear model by at most "
              f"{gap:.3g} standard deviations of the noise (limit {NONLINEAR_LIMIT:g}; slopes "
              f"up to {slope:.3g} rad): the small-deflection fit is used alone")
    return {"method": "small-deflection", "reason": reason, "nonlinearity": gap, "start": None,
            "max_slope": slope}


def run_finger(problem: FingerFitProblem, progress: Progress | None = None) -> RunOutput:
    """Fit c = 1/EI on knots (convex, small deflection), refine on the
    elastica if the data need it, and write the finger model."""
    data, st = problem.data, problem.settings
    t_start = time.perf_counter()
    knots = np.linspace(0.0, problem.length, st.knots)
    if progress:
        progress(f"convex fit: {len(data.observations)} measured values, {st.knots} knots, "
                 f"weight by {st.weight}")
    K, used = kernel(knots, data)
    convex = fit_compliance(K, data.values[used], data.sigmas[used], knots, used, st.monotone,
                            st.weight)
    choice = choose_method(problem, convex, progress)
    refinement = None
    fit = convex
    if choice["method"] == "elastica":
        if progress:
            progress("refining on the collocated elastica (CasADi + Ipopt)")
        start = choice["start"]
        refinement = refine(data, problem.length, convex, st.monotone, start, st.weight)
        fit = refinement.fit
    ok = refinement is None or refinement.success
    predictions = np.array([o.s for o in data.observations], dtype=float)
    predictions[fit.used] = fit.predictions
    student = np.full(len(data.observations), np.nan)
    student[fit.used] = fit.studentised
    flagged = np.abs(np.nan_to_num(student)) > FLAG_LIMIT
    # the profile, its band and where the data determine it
    c, c_sd = fit.c, fit.c_sd
    ei = 1.0 / np.maximum(c, 1e-300)
    lo_c, hi_c = c + BAND_Z * c_sd, c - BAND_Z * c_sd
    ei_low = 1.0 / lo_c
    ei_high = np.where(hi_c > 0, 1.0 / np.maximum(hi_c, 1e-300), np.inf)
    band = BAND_Z * c_sd / np.maximum(c, 1e-300)
    reach = data.reach
    determined = (knots <= reach + 1e-12) & (band <= DETERMINED_BAND)
    warnings = [data.note] if data.note else []
    if reach < problem.length - 1e-9:
        warnings.append(f"EI(s) past s = {reach:.4g} m is not determined by the data: no load "
                        f"and no measured point lies beyond it, so no measurement depends on "
                        f"it; the model there is the smoothness penalty's continuation "
                        f"(towards flat) of the fitted profile")
    for a, b in _ranges(knots, (knots <= reach + 1e-12) & ~determined):
        where = f"at s = {a:.4g} m" if a == b else f"on [{a:.4g}, {b:.4g}] m"
        warnings.append(f"EI(s) {where} is poorly determined: its 95 % band is wider than "
                        f"±{DETERMINED_BAND:.0%}")
    if flagged.any():
        lines = ", ".join(str(data.observations[i].line) for i in np.flatnonzero(flagged)[:20])
        warnings.append(f"{int(flagged.sum())} measured value(s) fit badly (|studentised "
                        f"residual| > {FLAG_LIMIT:g}): data file lines {lines}")
    noise = fit.selection.noise_scale
    if np.isfinite(noise) and noise > 2.0:
        warnings.append(f"the residuals are {noise:.3g} times the stated noise: the model does "
                        f"not explain the data, or fit.noise understates it")
    # the model file
    stiff, raised = safe_profile(knots, c)
    if raised:
        warnings.append(f"the fitted compliance reached zero (EI unbounded) at "
                        f"s = {', '.join(f'{v:.4g}' for v in knots[c < COMPLIANCE_FLOOR * np.median(c)])} m; "
                        f"the model file caps EI there at {1 / COMPLIANCE_FLOOR:g}x the "
                        f"profile's median")
    E = problem.E if problem.E is not None else 1.0
    ei_model = stiff.ei(knots)
    if st.model == "exponential":
        mask = determined if determined.sum() >= 3 else knots <= reach
        model_stiff: Stiffness = project(knots, ei_model, np.maximum(ei * band / BAND_Z, 1e-12),
                                         mask, problem.length, E, st.rates)
    else:
        model_stiff = TableI(E, tuple(float(v) for v in knots),
                             tuple(float(v) for v in ei_model / E))
    unit_note = ("E is the finger's modulus from the fit file; I(s) = EI(s) / E."
                 if problem.E is not None else
                 "Only EI(s) = E I(s) is measured: E is set to 1 Pa, so the I values are EI in "
                 "N m^2.")
    header = (f"Written by `design fit` ({problem.name}): EI(s) fitted to "
              f"{len(data.observations)} measured values in {problem.data_file.name} by the "
              f"{fit.method} model; {st.model} of I(s). {unit_note} Out of its plane the finger "
              f"gets a round section's rigidities (the default). EI is determined by the data "
              f"on {', '.join(f'[{a:.4g}, {b:.4g}]' for a, b in _ranges(knots, determined)) or 'no interval'} m "
              f"(see report.html).")
    text = finger_yaml(problem, model_stiff, E, header)
    check = Reader("finger.yaml")
    written = read_finger(check, yaml.safe_load(text), "", problem.data_file.parent)
    if not check.ok or written is None:
        ok = False
        warnings.append("the model file does not read back: " +
                        "; ".join(str(p) for p in check.problems))
        model_pred = np.full(len(data.observations), np.nan)
    else:
        model_pred = model_predictions(written.stiffness, problem.length, data, fit.method)
    elapsed = time.perf_counter() - t_start
    sig = data.sigmas
    model_gap = float(np.nanmax(np.abs(model_pred - predictions)[fit.used] / sig[fit.used]))
    if np.isfinite(model_gap) and model_gap > 1.0:
        warnings.append(f"the model file's {st.model} predicts the measurements up to "
                        f"{model_gap:.3g} standard deviations of the noise away from the fit")
    sel = convex.selection
    result = {
        "kind": "fit", "target": "finger", "name": problem.name, "toolkit_version": __version__,
        "units": {"length": "m", "force": "N", "angle": "rad", "EI": "N m^2",
                  "compliance": "1/(N m^2)", "time": "s"},
        "data_file": str(problem.data_file), "measurements": len(data.observations),
        "load_cases": len(data.loads), "length": problem.length, "E": problem.E,
        "method": fit.method, "method_reason": choice["reason"],
        "nonlinearity_sigma": choice["nonlinearity"], "max_slope_fitted": choice.get("max_slope"),
        "max_slope_measured": data.max_slope,
        "convex": {"solver": f"{SOLVER} via cvxpy", "why": SOLVER_WHY,
                   "weight_rule": sel.rule, "weight": sel.chosen.lam,
                   "weights_tried": sel.solves, "status": sel.status,
                   "solve_time_s": sel.solve_time_s, "setup_time_s": sel.setup_time_s,
                   "noise_scale": sel.noise_scale, "effective_parameters": sel.chosen.trace,
                   "monotone": st.monotone, "knots": st.knots},
        "elastica": None if refinement is None else {
            "solver": "Ipopt via CasADi (exact first and second derivatives)",
            "unknowns": refinement.unknowns, "build_time_s": refinement.build_time_s,
            "success": refinement.success,
            "solves": [{"weight": s.lam, "status": s.status, "success": s.success,
                        "iterations": s.iterations, "time_s": s.time_s}
                       for s in refinement.solves],
            "weight": fit.lam, "noise_scale": fit.selection.noise_scale,
            "effective_parameters": fit.selection.chosen.trace},
        "profile": {"s": knots, "EI": ei, "EI_low": ei_low, "EI_high": ei_high,
                    "band_relative": band, "determined": determined},
        "determined": _ranges(knots, determined), "reach": reach,
        "rms_residual": _rms_by_quantity(data, predictions),
        "flagged": [{"line": data.observations[i].line,
                     "quantity": data.observations[i].quantity,
                     "measured": data.observations[i].value, "predicted": predictions[i],
                     "studentised": student[i]} for i in np.flatnonzero(flagged)],
        "warnings": warnings,
        "model": {"file": "finger.yaml", "type": st.model, "E": E,
                  "max_difference_from_fit_sigma": model_gap,
                  "stiffness": model_stiff.describe()},
        "reference": None if problem.reference is None else problem.reference.describe(),
        "run_time_s": elapsed, "ok": ok,
    }
    rows = [{"line": o.line, "case": o.case, "F_N": data.loads[o.case].force,
             "alpha_rad": data.loads[o.case].alpha, "at_m": data.loads[o.case].at, "s_m": o.s,
             "quantity": o.quantity, "unit": "rad" if o.quantity == "psi" else "m",
             "measured": o.value, "sigma": o.sigma, "predicted": predictions[i],
             "model_file_predicted": model_pred[i], "residual": predictions[i] - o.value,
             "studentised": student[i], "flagged": bool(flagged[i])}
            for i, o in enumerate(data.observations)]
    profile = [{"s_m": s, "EI_N_m2": e, "EI_low_N_m2": lo, "EI_high_N_m2": hi,
                "model_EI_N_m2": float(written.stiffness.ei(s)) if written else None,
                "determined": bool(d)}
               for s, e, lo, hi, d in zip(knots, ei, ei_low, ei_high, determined)]
    weights = [{"weight": f.lam, "gcv": f.gcv, "residual_norm": float(np.linalg.norm(f.residual)),
                "roughness": f.roughness, "effective_parameters": f.trace,
                "chosen": f is fit.selection.chosen} for f in fit.selection.sweep]
    return RunOutput(result, {"measurements.csv": rows, "profile.csv": profile,
                              "weights.csv": weights},
                     ok=ok, files={"finger.yaml": text},
                     artifacts={"problem": problem, "fit": fit, "convex": convex,
                                "model": written, "model_predictions": model_pred})


def _rms_by_quantity(data: FingerData, predictions: np.ndarray) -> dict:
    out = {}
    for q in ("x", "y", "psi"):
        idx = [i for i, o in enumerate(data.observations) if o.quantity == q]
        if idx:
            r = predictions[idx] - data.values[idx]
            out[q] = float(np.sqrt(np.mean(r ** 2)))
    return out


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
