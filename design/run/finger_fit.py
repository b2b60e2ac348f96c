"""Running a finger fit: EI(s) from bench readings, the band and where the
data determine it, the warnings, and the finger model file (SI)."""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
import yaml

from design import __version__
from design.calibration.convex import BAND_Z, FLAG_LIMIT, SOLVER, ProfileFit, fit_compliance
from design.calibration.data import QUANTITIES, FingerData
from design.calibration.elastica import UniformFit, elastica_predictions, uniform_fit
from design.calibration.exponential import project
from design.calibration.kernel import KnotCompliance, kernel
from design.calibration.refinement import Refinement, refine
from design.io.fingers import read_finger
from design.io.fit_problem import FingerFitProblem
from design.io.reader import Reader
from design.physics.beam import Finger
from design.physics.stiffness import Stiffness, TableI
from design.run import Progress, RunOutput

#: the elastica refines the fit when it differs from the linear model by more
#: than this many standard deviations of the stated noise at some measurement
NONLINEAR_LIMIT = 1.0
#: EI counts as determined where its 95 % band is narrower than ± this fraction:
#: the accuracy a fit is held to where it calls EI determined (within 10 % of
#: the truth); a wider band, though it holds the truth, leaves room for an
#: error past that (tests/fit_benches.py, benchmarks/fit_bench.py)
DETERMINED_BAND = 0.10
#: a fitted compliance below this fraction of the profile's median is raised
#: to it in the model file (EI at most 100x the median, never infinite)
COMPLIANCE_FLOOR = 1e-2
#: the model file's table of I(s) has this many points per knot interval: a
#: cubic spline through the knots alone departs from the fit's compliance
#: (linear between knots) by more than the noise where EI changes fast (the
#: model file's predictions against the fit's, benchmarks/fit_bench.py)
TABLE_REFINEMENT = 2
#: residuals this many times the stated noise are warned of
NOISE_LIMIT = 2.0
SOLVER_WHY = ("Clarabel (interior point, through cvxpy): solves the QP's quadratic objective "
              "directly to ~1e-8 relative accuracy, enough to compare the residuals of "
              "neighbouring weights; OSQP (first-order ADMM) stops at 1e-5 tolerances and "
              "converges slowly past them")


@dataclass
class FingerFit:
    """What fitting did: the small-deflection fit (None without y or psi
    readings), the model chosen and why, the uniform elastica fit the
    refinement starts from and the refinement (None where the
    small-deflection fit stands), and the fit used."""

    convex: ProfileFit | None
    choice: dict
    start: UniformFit | None
    refinement: Refinement | None
    fit: ProfileFit

    @property
    def ok(self) -> bool:
        return self.refinement is None or self.refinement.success


@dataclass
class ProfileSummary:
    """The fitted EI (N m²) at the knots (m) with its 95 % band, the band's
    relative half-width, where EI is determined (band within
    ±:data:`DETERMINED_BAND`, no further than the data reach) and where each
    kind of reading alone would determine it."""

    knots: np.ndarray
    ei: np.ndarray
    low: np.ndarray
    high: np.ndarray
    band: np.ndarray
    determined: np.ndarray
    reach: float
    alone: dict[str, np.ndarray]


# ------------------------------------------------------------------ fitting

def fit_finger(problem: FingerFitProblem, progress: Progress | None = None) -> FingerFit:
    """The small-deflection fit (convex), and the elastica refinement where
    the data need it (or ask for it)."""
    data, st = problem.data, problem.settings
    knots = np.linspace(0.0, problem.length, st.knots)
    K, used = kernel(knots, data)
    convex = None
    if used:
        _say(progress, f"convex fit: {len(used)} deflections and slopes, {st.knots} knots, "
                       f"weight by {st.weight}")
        convex = fit_compliance(K, data.values[used], data.sigmas[used], knots, used,
                                st.monotone, st.weight)
    choice = choose_method(problem, convex, progress)
    if choice["method"] == "small-deflection":
        return FingerFit(convex, choice, None, None, convex)
    _say(progress, "uniform EI on the elastica (where the refinement starts)")
    start = uniform_fit(data, problem.length)
    _say(progress, "refining on the collocated elastica (CasADi + Ipopt) along a path of weights")
    c0 = np.full(knots.size, 1.0 / start.ei)
    refinement = refine(data, problem.length, knots, c0, 1.0 / start.ei, start.solutions,
                        st.monotone, st.weight)
    return FingerFit(convex, choice, start, refinement, refinement.fit)


def choose_method(problem: FingerFitProblem, convex: ProfileFit | None,
                  progress: Progress | None) -> dict:
    """Whether the small-deflection fit is enough: the elastica through its
    profile against the linear model, in standard deviations of the noise."""
    data, asked = problem.data, problem.settings.method
    if asked == "small-deflection":
        return {"method": "small-deflection", "reason": "asked for (fit.method)",
                "nonlinearity": None, "max_slope": None}
    if convex is None:
        return {"method": "elastica", "nonlinearity": None, "max_slope": None,
                "reason": "only x readings: the small-deflection model has no x (to first "
                          "order a point moves across the finger, not along it)"}
    _say(progress, "checking the linear model against the elastica")
    stiff, _ = safe_profile(convex.knots, convex.c)
    el, sols = elastica_predictions(Finger(problem.length, stiff), data)
    gap = float(np.max(np.abs(el - linear_predictions(convex, data)) / data.sigmas))
    slope = float(max(np.max(np.abs(s.psi)) for s in sols))
    measure = (f"the elastica through the small-deflection fit differs from the linear "
               f"model by up to {gap:.3g} standard deviations of the noise (limit "
               f"{NONLINEAR_LIMIT:g}; slopes up to {np.degrees(slope):.3g} deg)")
    if asked == "elastica":
        reason = "asked for (fit.method)"
    elif gap > NONLINEAR_LIMIT:
        reason = measure + ": refined on the elastica"
    else:
        reason = measure + ": the small-deflection fit is used alone"
    method = "small-deflection" if asked == "auto" and gap <= NONLINEAR_LIMIT else "elastica"
    return {"method": method, "reason": reason, "nonlinearity": gap, "max_slope": slope}


def linear_predictions(fit: ProfileFit, data: FingerData) -> np.ndarray:
    """Every observation's small-deflection value (x: the point's s)."""
    K, used = kernel(fit.knots, data)
    out = np.array([o.s for o in data.observations])
    out[used] = K @ fit.c
    return out


def _say(progress: Progress | None, message: str) -> None:
    if progress:
        progress(message)


# ------------------------------------------------------------- the profile

def summarise(problem: FingerFitProblem, fit: ProfileFit) -> ProfileSummary:
    """EI, its band and where the data determine it, in all and by kind of
    reading (the band the readings of one kind alone would give, at the same
    weight and noise scale)."""
    data = problem.data
    low, high = fit.ei_band()
    reach = data.reach
    reached = fit.knots <= reach + 1e-12
    kinds = [data.observations[i].quantity for i in fit.used]
    alone = {}
    for q in QUANTITIES:
        rows = np.flatnonzero(np.array(kinds) == q)
        if rows.size:
            alone[q] = reached & (fit.band_from(rows) <= DETERMINED_BAND)
    return ProfileSummary(fit.knots, 1.0 / np.maximum(fit.c, 1e-300), low, high, fit.band,
                          reached & (fit.band <= DETERMINED_BAND), reach, alone)


def determined_by(summary: ProfileSummary) -> dict[str, list[tuple[float, float]]]:
    """Where each kind of reading alone determines EI, and where only the
    kinds together do (intervals in m)."""
    out = {q: _ranges(summary.knots, mask) for q, mask in summary.alone.items()}
    if len(summary.alone) > 1:
        alone_any = np.any(list(summary.alone.values()), axis=0)
        out["together"] = _ranges(summary.knots, summary.determined & ~alone_any)
    return out


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


def finger_warnings(problem: FingerFitProblem, ff: FingerFit, summary: ProfileSummary,
                    flagged: np.ndarray) -> list[str]:
    """What the user must know about the fit: readings taken as noise, where
    EI is not determined, badly fitted readings, residuals past the noise,
    a refinement that did not converge."""
    data, fit = problem.data, ff.fit
    warnings = [data.note] if data.note else []
    ref = ff.refinement
    if ref is not None and not ref.success:
        warnings.append(f"the elastica refinement did not converge: {ref.ended}")
    elif ref is not None and ref.failed_at is not None:
        warnings.append(f"the path of weights ended early, {ref.ended}: the weight was chosen "
                        f"among the {len(ref.solves) - 1} larger ones solved, and a smaller one "
                        f"might fit better")
    if summary.reach < problem.length - 1e-9:
        warnings.append(f"EI(s) past s = {summary.reach:.4g} m is not determined by the data: "
                        f"no load and no measured point lies beyond it, so no measurement "
                        f"depends on it; the model there is the smoothness penalty's "
                        f"continuation of the fitted profile")
    reached = summary.knots <= summary.reach + 1e-12
    for a, b in _ranges(summary.knots, reached & ~summary.determined):
        where = f"at s = {a:.4g} m" if a == b else f"on [{a:.4g}, {b:.4g}] m"
        warnings.append(f"EI(s) {where} is poorly determined: its 95 % band is wider than "
                        f"±{DETERMINED_BAND:.0%}")
    if flagged.any():
        lines = ", ".join(str(data.observations[i].line) for i in np.flatnonzero(flagged)[:20])
        warnings.append(f"{int(flagged.sum())} measured value(s) fit badly (|studentised "
                        f"residual| > {FLAG_LIMIT:g}): data file lines {lines}")
    noise = fit.selection.noise_scale
    if np.isfinite(noise) and noise > NOISE_LIMIT:
        warnings.append(f"the residuals are {noise:.3g} times the stated noise: the model does "
                        f"not explain the data, or fit.noise understates it")
    return warnings


# --------------------------------------------------------------- the model

@dataclass
class ModelFile:
    """The finger model file as written, the finger it reads back as (None
    if it does not), its predictions of the readings and how far they are
    from the fit's (in standard deviations of the noise), and its warnings."""

    text: str
    stiffness: Stiffness
    written: Finger | None
    predictions: np.ndarray
    gap: float
    warnings: list[str]


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


def model_file(problem: FingerFitProblem, fit: ProfileFit, summary: ProfileSummary,
               predictions: np.ndarray) -> ModelFile:
    """The model file of the fitted profile (a table of I(s), or the
    exponential family projected onto it), read back through the finger
    reader, and its predictions against the fit's (``predictions``)."""
    st, data, knots = problem.settings, problem.data, summary.knots
    stiff, raised = safe_profile(knots, fit.c)
    warnings = []
    if raised:
        low = knots[fit.c < COMPLIANCE_FLOOR * np.median(fit.c)]
        warnings.append(f"the fitted compliance reached zero (EI unbounded) at "
                        f"s = {', '.join(f'{v:.4g}' for v in low)} m; the model file caps EI "
                        f"there at {1 / COMPLIANCE_FLOOR:g}x the profile's median")
    E = problem.E if problem.E is not None else 1.0
    ei_model = stiff.ei(knots)
    if st.model == "exponential":
        mask = summary.determined if summary.determined.sum() >= 3 else knots <= summary.reach
        model: Stiffness = project(knots, ei_model,
                                   np.maximum(summary.ei * summary.band / BAND_Z, 1e-12), mask,
                                   problem.length, E, st.rates)
    else:
        table = np.linspace(0.0, problem.length, TABLE_REFINEMENT * (knots.size - 1) + 1)
        model = TableI(E, tuple(float(v) for v in table),
                       tuple(float(v) for v in stiff.ei(table) / E))
    unit_note = ("E is the finger's modulus from the fit file; I(s) = EI(s) / E."
                 if problem.E is not None else
                 "Only EI(s) = E I(s) is measured: E is set to 1 Pa, so the I values are EI in "
                 "N m^2.")
    spans = ", ".join(f"[{a:.4g}, {b:.4g}]" for a, b in _ranges(knots, summary.determined))
    header = (f"Written by `design fit` ({problem.name}): EI(s) fitted to "
              f"{len(data.observations)} measured values in {problem.data_file.name} by the "
              f"{fit.method} model; {st.model} of I(s). {unit_note} Out of its plane the finger "
              f"gets a round section's rigidities (the default). EI is determined by the data "
              f"on {spans or 'no interval'} m (see report.html).")
    text = finger_yaml(problem, model, E, header)
    check = Reader("finger.yaml")
    written = read_finger(check, yaml.safe_load(text), "", problem.data_file.parent)
    if not check.ok or written is None:
        warnings.append("the model file does not read back: "
                        + "; ".join(str(p) for p in check.problems))
        return ModelFile(text, model, None, np.full(len(data.observations), np.nan), np.nan,
                         warnings)
    pred = model_predictions(written.stiffness, problem.length, data, fit.method)
    gap = float(np.max(np.abs(pred - predictions)[fit.used] / data.sigmas[fit.used]))
    if gap > 1.0:
        warnings.append(f"the model file's {st.model} predicts the measurements up to "
                        f"{gap:.3g} standard deviations of the noise away from the fit")
    return ModelFile(text, model, written, pred, gap, warnings)


# ----------------------------------------------------------------- the run

def run_finger(problem: FingerFitProblem, progress: Progress | None = None) -> RunOutput:
    """Fit c = 1/EI on knots (convex, small deflection), refine on the
    elastica if the data need it, and write the finger model."""
    t_start = time.perf_counter()
    data = problem.data
    ff = fit_finger(problem, progress)
    fit = ff.fit
    predictions = np.array([o.s for o in data.observations], dtype=float)
    predictions[fit.used] = fit.predictions
    student = np.full(len(data.observations), np.nan)
    student[fit.used] = fit.studentised
    flagged = np.abs(np.nan_to_num(student)) > FLAG_LIMIT
    summary = summarise(problem, fit)
    warnings = finger_warnings(problem, ff, summary, flagged)
    model = model_file(problem, fit, summary, predictions)
    warnings += model.warnings
    ok = ff.ok and model.written is not None
    result = finger_result(problem, ff, summary, model, predictions, student, flagged,
                           warnings, ok, time.perf_counter() - t_start)
    return RunOutput(result, finger_tables(problem, ff, summary, model, predictions, student,
                                           flagged),
                     ok=ok, files={"finger.yaml": model.text},
                     artifacts={"problem": problem, "fit": fit, "convex": ff.convex,
                                "model": model.written, "model_predictions": model.predictions,
                                "summary": summary})


def finger_result(problem: FingerFitProblem, ff: FingerFit, summary: ProfileSummary,
                  model: ModelFile, predictions: np.ndarray, student: np.ndarray,
                  flagged: np.ndarray, warnings: list[str], ok: bool, elapsed: float) -> dict:
    """result.json of a finger fit (SI)."""
    data, st, fit = problem.data, problem.settings, ff.fit
    return {
        "kind": "fit", "target": "finger", "name": problem.name, "toolkit_version": __version__,
        "units": {"length": "m", "force": "N", "angle": "rad", "EI": "N m^2",
                  "compliance": "1/(N m^2)", "time": "s"},
        "data_file": str(problem.data_file), "measurements": len(data.observations),
        "readings": {q: sum(o.quantity == q for o in data.observations) for q in QUANTITIES},
        "load_cases": len(data.loads), "length": problem.length, "E": problem.E,
        "method": fit.method, "method_reason": ff.choice["reason"],
        "nonlinearity_sigma": ff.choice["nonlinearity"],
        "max_slope_fitted": ff.choice["max_slope"], "max_slope_measured": data.max_slope,
        "convex": None if ff.convex is None else _convex_result(ff.convex, st),
        "elastica": None if ff.refinement is None else _elastica_result(ff),
        "profile": {"s": summary.knots, "EI": summary.ei, "EI_low": summary.low,
                    "EI_high": summary.high, "band_relative": summary.band,
                    "determined": summary.determined},
        "determined": _ranges(summary.knots, summary.determined), "reach": summary.reach,
        "determined_band": DETERMINED_BAND, "determined_by": determined_by(summary),
        "rms_residual": _rms_by_quantity(data, predictions),
        "noise_scale": fit.selection.noise_scale,
        "flagged": [{"line": data.observations[i].line,
                     "quantity": data.observations[i].quantity,
                     "measured": data.observations[i].value, "predicted": predictions[i],
                     "studentised": student[i]} for i in np.flatnonzero(flagged)],
        "warnings": warnings,
        "model": {"file": "finger.yaml", "type": st.model,
                  "E": problem.E if problem.E is not None else 1.0,
                  "max_difference_from_fit_sigma": model.gap,
                  "stiffness": model.stiffness.describe()},
        "reference": None if problem.reference is None else problem.reference.describe(),
        "run_time_s": elapsed, "ok": ok,
    }


def _convex_result(convex: ProfileFit, st) -> dict:
    sel = convex.selection
    return {"solver": f"{SOLVER} via cvxpy", "why": SOLVER_WHY, "weight_rule": sel.rule,
            "weight": sel.chosen.lam, "weights_tried": sel.solves, "status": sel.status,
            "solve_time_s": sel.solve_time_s, "setup_time_s": sel.setup_time_s,
            "noise_scale": sel.noise_scale, "effective_parameters": sel.chosen.trace,
            "monotone": st.monotone, "knots": st.knots}


def _elastica_result(ff: FingerFit) -> dict:
    ref, start, sel = ff.refinement, ff.start, ff.fit.selection
    return {"solver": "Ipopt via CasADi (Gauss-Newton Hessian, exact first derivatives)",
            "unknowns": ref.unknowns, "build_time_s": ref.build_time_s,
            "success": ref.success,
            "start": {"uniform_EI": start.ei, "elastica_solves": start.evaluations,
                      "time_s": start.time_s},
            "solves": [{"weight": s.lam, "status": s.status, "success": s.success,
                        "iterations": s.iterations, "time_s": s.time_s} for s in ref.solves],
            "chosen_solve": ref.chosen, "path_ended": ref.ended,
            "weight": sel.chosen.lam, "noise_scale": sel.noise_scale,
            "effective_parameters": sel.chosen.trace,
            "band_also_covers_weight": sel.alternative.chosen.lam if sel.alternative else None}


def finger_tables(problem: FingerFitProblem, ff: FingerFit, summary: ProfileSummary,
                  model: ModelFile, predictions: np.ndarray, student: np.ndarray,
                  flagged: np.ndarray) -> dict[str, list[dict]]:
    """measurements.csv, profile.csv and weights.csv of a finger fit (SI)."""
    data, fit = problem.data, ff.fit
    rows = [{"line": o.line, "case": o.case, "F_N": data.loads[o.case].force,
             "alpha_rad": data.loads[o.case].alpha, "at_m": data.loads[o.case].at, "s_m": o.s,
             "quantity": o.quantity, "unit": "rad" if o.quantity == "psi" else "m",
             "measured": o.value, "sigma": o.sigma, "predicted": predictions[i],
             "model_file_predicted": model.predictions[i], "residual": predictions[i] - o.value,
             "studentised": student[i], "flagged": bool(flagged[i])}
            for i, o in enumerate(data.observations)]
    written = model.written
    profile = [{"s_m": s, "EI_N_m2": e, "EI_low_N_m2": lo, "EI_high_N_m2": hi,
                "model_EI_N_m2": float(written.stiffness.ei(s)) if written else None,
                "determined": bool(d),
                **{f"determined_by_{q}_alone": bool(m[k]) for q, m in summary.alone.items()}}
               for k, (s, e, lo, hi, d) in enumerate(zip(summary.knots, summary.ei, summary.low,
                                                          summary.high, summary.determined))]
    weights = [{"weight": f.lam, "gcv": f.gcv, "residual_norm": float(np.linalg.norm(f.residual)),
                "roughness": f.roughness, "effective_parameters": f.trace,
                "chosen": f is fit.selection.chosen} for f in fit.selection.sweep]
    return {"measurements.csv": rows, "profile.csv": profile, "weights.csv": weights}


def _rms_by_quantity(data: FingerData, predictions: np.ndarray) -> dict:
    out = {}
    for q in QUANTITIES:
        idx = [i for i, o in enumerate(data.observations) if o.quantity == q]
        if idx:
            r = predictions[idx] - data.values[idx]
            out[q] = float(np.sqrt(np.mean(r ** 2)))
    return out
