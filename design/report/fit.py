"""Reports of fit runs: the fitted EI(s) with its band, measured against
predicted values, residuals and the weight's choice; or the belt's log
against its fits."""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

from design.calibration.convex import FLAG_LIMIT
from design.report.page import Page

MM = 1e3
READING_NAMES = {"x": "x", "y": "y", "psi": "slope"}


def _closing(page: Page, result: dict) -> None:
    page.section("Reproduce this run", "reproduce")
    source = result.get("scene_file")
    page.text(f"Toolkit version {result['toolkit_version']}. "
              + (f"Command: design fit {source}" if source else
                 "The fit problem was given as content from Python, not as a file."))


def _warnings(page: Page, warnings: list[str]) -> None:
    page.section("Warnings", "warnings")
    if not warnings:
        page.text("None: the data determine the profile where the model uses it.")
    for w in warnings:
        page.text("• " + w)


def finger_page(result: dict, artifacts: dict) -> Page:
    page = Page(f"Finger fit: {result['name']}")
    if result["ok"]:
        page.banner(f"EI(s) fitted by the {result['method']} model to {result['measurements']} "
                    f"measured values; model written to finger.yaml", "passed")
    else:
        page.banner("The fit did not succeed: see the warnings", "failed")
    _method(page, result, artifacts["fit"])
    _warnings(page, result["warnings"])
    _profile(page, result, artifacts)
    _residuals(page, result, artifacts)
    _weight(page, artifacts["fit"])
    _closing(page, result)
    return page


def _method(page: Page, result: dict, fit) -> None:
    """How the fit was made: the model and why, each solver's work, the noise."""
    page.section("Method", "method")
    page.text(f"Model used: {result['method']}. Why: {result['method_reason']}.")
    cv = result["convex"]
    if cv:
        page.text(f"Convex step: compliance c = 1/EI on {cv['knots']} knots, c ≥ 0"
                  f"{', EI monotone ' + cv['monotone'] if cv['monotone'] else ''}, roughness "
                  f"penalty weighted by {cv['weight_rule']} (weight {cv['weight']:.4g} of "
                  f"{cv['weights_tried']} tried); solver {cv['solver']}: {cv['why']}. "
                  f"Solve time {cv['solve_time_s']:.3f} s for the sweep, status {cv['status']}.")
    el = result["elastica"]
    if el:
        st = el["start"]
        solves = "; ".join(f"weight {s['weight']:.4g}: {s['status']}, {s['iterations']} "
                           f"iterations, {s['time_s']:.3f} s" for s in el["solves"])
        page.text(f"Elastica refinement of ln c at the knots (penalty on its second "
                  f"differences): started from the uniform EI that fits the readings on the "
                  f"elastica, {st['uniform_EI']:.4g} N m² ({st['elastica_solves']} elastica "
                  f"solves, {st['time_s']:.2f} s); {el['solver']}, {el['unknowns']} unknowns, "
                  f"built in {el['build_time_s']:.2f} s; weights from large to small, each "
                  f"solve starting from the last: {solves}. The path ended because "
                  f"{el['path_ended']}; weight {el['weight']:.4g} chosen by "
                  f"{fit.selection.rule} on the elastica linearised at each solution."
                  + ("" if el["band_also_covers_weight"] is None else
                     f" It is the path's first, all but the best exponential profile, and "
                     f"GCV cannot tell it from the fit at weight "
                     f"{el['band_also_covers_weight']:.4g}: the band covers that fit and its "
                     f"band too."))
    rms = ", ".join(f"{q}: {np.degrees(v):.3g} deg" if q == "psi" else f"{q}: {v * MM:.3g} mm"
                    for q, v in result["rms_residual"].items())
    page.text(f"Noise: the residuals are {fit.selection.noise_scale:.3g} times the stated "
              f"standard deviations; RMS residuals {rms}.")


def _profile(page: Page, result: dict, artifacts: dict) -> None:
    """EI(s) with its band, the model file's, the reference, and which readings determine it."""
    problem = artifacts["problem"]
    page.section("Fitted EI(s)", "profile")
    band = f"±{100 * result['determined_band']:.0f} %"
    page.text(f"Which readings determine EI(s) (its band within {band} from "
              f"them alone): "
              + determination_text(result["determined_by"]) + ".")
    prof = result["profile"]
    s = np.asarray(prof["s"])
    fig = Figure(figsize=(8, 4.4))
    ax = fig.subplots()
    lo, hi = np.asarray(prof["EI_low"], float), np.asarray(prof["EI_high"], float)
    top = np.nanmax(np.where(np.isfinite(hi), hi, np.nan)) if np.isfinite(hi).any() else None
    hi_plot = np.where(np.isfinite(hi), hi, 10 * np.nanmax(prof["EI"]))
    ax.fill_between(s * MM, lo, hi_plot, color="C0", alpha=0.2, label="95 % band")
    ax.plot(s * MM, prof["EI"], "C0.-", label=f"fitted ({result['method']})")
    model = artifacts.get("model")
    fine = np.linspace(0.0, problem.length, 400)
    if model is not None:
        ax.plot(fine * MM, model.stiffness.ei(fine), "C1-", lw=1,
                label=f"model file ({result['model']['type']})")
    if problem.reference is not None:
        ax.plot(fine * MM, problem.reference.stiffness.ei(fine), "k--", lw=1, label="reference")
    for a, b in result["determined"]:
        ax.axvspan(a * MM, b * MM, color="0.9", zorder=0)
    ax.axvline(result["reach"] * MM, color="C3", ls=":", label="last loaded/measured point")
    ax.set_yscale("log")
    if top is not None:
        ax.set_ylim(0.5 * np.nanmin(lo), 2 * max(top, np.nanmax(prof["EI"])))
    ax.set_xlabel("arc length s (mm)")
    ax.set_ylabel("EI (N m²)")
    ax.legend(fontsize=8)
    page.figure(fig, "ei_profile", "Fitted EI(s) with its 95 % band (grey: where the data "
                f"determine it, band within {band})")


def determination_text(determined_by: dict) -> str:
    """Which readings determined which part of EI(s), in words (intervals in mm)."""
    def where(intervals):
        return ", ".join(f"[{a * MM:.4g}, {b * MM:.4g}] mm" for a, b in intervals) or "nowhere"

    parts = [f"the {READING_NAMES[q]} readings alone on {where(v)}"
             for q, v in determined_by.items() if q != "together"]
    if "together" in determined_by:
        parts.append(f"only all of them together on {where(determined_by['together'])}")
    return "; ".join(parts)


def _residuals(page: Page, result: dict, artifacts: dict) -> None:
    """Readings against predictions, the studentised residuals, the flagged readings."""
    data, fit = artifacts["problem"].data, artifacts["fit"]
    page.section("Measured against predicted", "residuals")
    obs = data.observations
    pred = np.array(result_predictions(result, artifacts))
    student = fit.studentised
    fig = Figure(figsize=(12, 4.4))
    left, right = fig.subplots(1, 2)
    for k in range(len(data.loads)):
        for q, mark in (("y", "o"), ("x", "s")):
            idx = sorted((i for i, o in enumerate(obs) if o.case == k and o.quantity == q),
                         key=lambda i: obs[i].s)
            if not idx:
                continue
            value = (lambda i: obs[i].value) if q == "y" else (lambda i: obs[i].s - obs[i].value)
            guess = (lambda i: pred[i]) if q == "y" else (lambda i: obs[i].s - pred[i])
            line = left.plot([obs[i].s * MM for i in idx], [guess(i) * MM for i in idx],
                             "-" if q == "y" else ":", lw=1)[0]
            left.plot([obs[i].s * MM for i in idx], [value(i) * MM for i in idx], mark,
                      ms=3, color=line.get_color(), mfc="none" if q == "x" else None)
    left.set_xlabel("measured point s (mm)")
    left.set_ylabel("deflection y; shortening s - x (mm)")
    left.set_title("points: measured (o y, □ s - x); lines: predicted", fontsize=9)
    right.axhspan(-FLAG_LIMIT, FLAG_LIMIT, color="0.92")
    right.plot(range(len(fit.used)), student, ".", ms=4)
    bad = np.abs(student) > FLAG_LIMIT
    right.plot(np.flatnonzero(bad), student[bad], "rx", label="flagged")
    right.set_xlabel("measurement (data order)")
    right.set_ylabel("studentised residual")
    right.legend(fontsize=8)
    page.figure(fig, "residuals", "Deflections and shortenings of every load case, measured "
                f"and predicted; studentised residuals (flagged beyond ±{FLAG_LIMIT:g})")
    if result["flagged"]:
        page.table([{"line": f["line"], "quantity": f["quantity"], "measured": f["measured"],
                     "predicted": f["predicted"], "studentised": f["studentised"]}
                    for f in result["flagged"]], "Badly fitted measurements (SI)",
                   "flagged-table")


def _weight(page: Page, fit) -> None:
    """The weight's choice: GCV and the L-curve along the sweep or path."""
    page.section("Choice of the weight", "weight")
    sweep = fit.selection.sweep
    fig = Figure(figsize=(12, 4))
    g, lc = fig.subplots(1, 2)
    lam = [f.lam for f in sweep]
    g.loglog(lam, [f.gcv for f in sweep], ".-")
    g.axvline(fit.lam, color="C3", label="chosen")
    g.set_xlabel("weight λ")
    g.set_ylabel("GCV V(λ)")
    g.legend(fontsize=8)
    lc.loglog([np.linalg.norm(f.residual) for f in sweep], [f.roughness for f in sweep], ".-")
    ch = fit.selection.chosen
    lc.loglog([np.linalg.norm(ch.residual)], [ch.roughness], "ro")
    lc.set_xlabel("‖r / σ‖")
    lc.set_ylabel("‖D c / c_ref‖" if not fit.log else "‖D ln c‖")
    page.figure(fig, "weight", f"The weight sweep of the {fit.method} fit: GCV and the L-curve "
                f"(red: chosen by {fit.selection.rule})")


def result_predictions(result: dict, artifacts: dict) -> list[float]:
    fit, data = artifacts["fit"], artifacts["problem"].data
    out = [o.s for o in data.observations]
    for i, p in zip(fit.used, fit.predictions):
        out[i] = p
    return out


def belt_page(result: dict, artifacts: dict) -> Page:
    problem, ramp, mono = artifacts["problem"], artifacts["ramp"], artifacts["monotone"]
    page = Page(f"Belt fit: {result['name']}")
    f = result["fitted"]
    if result["decelerates"]:
        text = (f"Belt slows from {f['speed']:.4g} to {f['final_speed']:.4g} m/s at "
                f"{f['rate']:.3g} m/s² from t = {f['start_time']:.4g} s")
    else:
        text = f"No significant slow-down: constant {f['speed']:.4g} m/s"
    page.banner(text + "; model written to conveyor.yaml",
                "passed" if result["ok"] else "failed")
    page.section("Fit", "fit")
    page.text(f"{result['samples']} samples. Conveyor model (constant, ramp, constant) by "
              f"least squares: RMS {ramp.rms:.3g} m/s. Monotone piecewise-linear check on "
              f"{problem.knots} knots ({result['monotone']['solver']}, "
              f"{result['monotone']['solve_time_s']:.3f} s): RMS {mono.rms:.3g} m/s. Times on "
              f"the simulation's clock: the log's t = {problem.time_zero:g} s is t = 0.")
    if result["comparison"]:
        page.table(result["comparison"], "Fitted against the stated values (SI)",
                   "comparison-table")
    _warnings(page, result["warnings"])
    page.section("Log and fits", "figure")
    fig = Figure(figsize=(12, 4.4))
    a, b = fig.subplots(1, 2)
    a.plot(problem.t, problem.v, ".", ms=3, color="0.5", label="log")
    a.plot(problem.t, mono.predictions, "C0-", lw=1, label="monotone fit")
    a.plot(problem.t, ramp.predictions, "C3-", lw=1.5, label="conveyor model")
    a.set_xlabel("t (s, log clock)")
    a.set_ylabel("v (m/s)")
    a.legend(fontsize=8)
    b.plot(problem.t, problem.v - ramp.predictions, ".", ms=3)
    b.axhline(0, color="k", lw=0.5)
    b.set_xlabel("t (s, log clock)")
    b.set_ylabel("residual (m/s)")
    page.figure(fig, "belt", "The encoder log with the monotone fit and the conveyor model; "
                "the model's residuals")
    _closing(page, result)
    return page


def write_fit(out_dir, output) -> list:
    """Write a fit run's folder: result.json, its tables, the model file,
    then the report and its figures (see :func:`design.report.page.write_report`)."""
    from design.io.results import output_files
    from design.report.page import write_report

    r, a = output.result, output.artifacts
    page = finger_page(r, a) if r["target"] == "finger" else belt_page(r, a)
    return write_report(out_dir, page, output_files(r, output.tables, output.files))
