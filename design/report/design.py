"""The report of a design run (``design solve``)."""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

from design.report.grasp import (animation_section, grasp_figures, reproduce_section,
                                 summary_rows)
from design.report.display import shown
from design.report.page import Page
from design.solvers.grasp.simulation import GraspRun
from design.solvers.optimize.feasibility import answered
from design.solvers.optimize.model_check import check_text
from design.solvers.optimize.robustness import robustness_text
from design.solvers.optimize.profile import profile_rows
from design.solvers.optimize.variables import units


#: how the report names a finger model
MODEL_WORDS = {"spatial": "spatial rods (bending both ways and twisting: the validated model)",
               "planar": "the thesis's planar beams (rigid out of their bending planes)",
               "planar-thesis": "the thesis's planar beams with its chapter III friction"}


def verification_rows(result: dict) -> list[dict]:
    """Optimiser against the independent simulation, with each check's verdict."""
    v = result["verification"]
    # a claim the optimiser could not evaluate is NaN, null in result.json: not passed
    difference = v["hold_time_relative_difference"]
    hold_ok = difference is not None and difference <= v["hold_tolerance"]
    force_ok = v["max_finger_force_N"] <= v["cap_N"] * (1 + v["cap_tolerance"])
    return [
        {"check": "longest N = 0 hold (s)",
         "optimiser or limit": "not evaluated" if v["optimiser_hold_time_s"] is None
         else v["optimiser_hold_time_s"],
         "independent simulation": v["hold_time_s"],
         "allowed": f"within {100 * v['hold_tolerance']:g} %",
         "difference": "not evaluated" if difference is None else difference,
         "passed": hold_ok},
        {"check": "peak finger force (N), against the cap", "optimiser or limit": v["cap_N"],
         "independent simulation": v["max_finger_force_N"],
         "allowed": f"≤ cap + {100 * v['cap_tolerance']:g} %",
         "difference": v["max_finger_force_N"] / v["cap_N"] - 1, "passed": force_ok}]


def convergence_figure(history: list[dict]) -> Figure:
    """Ipopt's hold time and constraint violation at every iteration, outer
    trust-region iterations one after another."""
    fig = Figure(figsize=(11, 4.2))
    hold, viol = fig.subplots(1, 2)
    offset = 0
    for outer in history:
        steps = outer.get("history") or []
        if not steps:
            continue
        k = offset + np.arange(len(steps))
        label = f"outer {outer['iteration']}" + (" (accepted)" if outer.get("accepted") else "")
        hold.plot(k, [s["hold_time_s"] for s in steps], label=label)
        viol.semilogy(k, [max(s["violation"], 1e-12) for s in steps])
        offset += len(steps)
    for ax, label in ((hold, "NLP hold time (s)"), (viol, "largest constraint violation")):
        ax.set_xlabel("Ipopt iteration (all outer iterations in turn)")
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
    hold.legend(fontsize=8)
    return fig


def pareto_figure(rows: list[dict], baseline: dict) -> Figure:
    fig = Figure(figsize=(7, 4.5))
    ax = fig.add_subplot(1, 1, 1)
    cap = [r["cap_N"] for r in rows]
    ax.plot(cap, [r["verified_hold_time_s"] for r in rows], "o-", label="verified")
    ax.plot(cap, [r["optimiser_hold_time_s"] for r in rows], "x--", label="optimiser")
    ax.plot([baseline["max_finger_force_N"]], [baseline["hold_time_s"]], "ks", label="baseline")
    for r in rows:
        if not r["passed"]:
            ax.annotate("failed", (r["cap_N"], r["verified_hold_time_s"]), color="r")
    ax.set_xlabel("bruise cap on every finger (N)")
    ax.set_ylabel("longest N = 0 hold (s)")
    ax.grid(alpha=0.3)
    ax.legend()
    return fig


def profile_table(page: Page, profile: dict) -> None:
    """The table "Where the time went" (result.json's ``profile``) and the
    run's peak memory, cores and load."""
    m = profile["machine"]
    load = ", ".join(f"{x:.2f}" for x in m["load_average_at_start"])
    page.text(f"Where the time went: {profile['wall_time_s']:.1f} s of wall time in all "
              f"({profile.get('cpu_time_s', float('nan')):.1f} s of CPU time), peak memory "
              f"{profile['peak_memory_MiB']:.0f} MiB, on {m['cpus']} cores with a load average "
              f"of {load} at the start. The phases do not overlap and add up to "
              "the total with the unaccounted rest; rows marked ↳ break down the Ipopt phase "
              "above them (CasADi's statistics) and are not added again. The contact "
              "rootfinders' time is inside nlp_g and nlp_jac_g.")
    page.table(profile_rows(profile), "Where the time went", "profile-table")


def population_section(page: Page, population: dict) -> None:
    """Each bird under the baseline, the single-bird optimum and the robust optimum."""
    page.section("Birds of the population", "population")
    holds, limiting = population["hold_time_s"], population["limiting_bird"]
    aggregate = "the shortest hold" if population["objective"] == "worst" else \
        "the weighted mean hold"
    page.text(f"Objective: {aggregate} over the birds; each bird's cap is given beside it. "
              f"The single-bird optimum is {population['single_bird']} optimised alone (cap "
              f"{population['single_bird_cap_N']:.2f} N). Population hold: baseline "
              f"{holds['baseline']:.4f} s (limited by {limiting['baseline']}), single-bird "
              f"optimum {holds['single_bird_optimum']:.4f} s ({limiting['single_bird_optimum']}"
              f"{'' if population['within_caps']['single_bird_optimum'] else ', breaks a cap'}"
              f"), robust optimum {holds['robust_optimum']:.4f} s "
              f"({limiting['robust_optimum']}). Every number is from the independent "
              f"simulation at 4x the optimiser's resolution."
              + (f" The robust optimum is {population['robust_optimum_is']}."
                 if population.get("robust_optimum_is") else ""))
    page.table(population["birds"], "Hold (s), peak finger force (N) and jam of every bird",
               "population-table")


def screen_table(page: Page, search: dict) -> None:
    """The feasibility screen's starts: where each ended, and how far from the limits."""
    beyond = search["starts"][0].get("beyond_s")
    page.text(f"Feasibility screen (design/solvers/optimize/feasibility.py): the pattern "
              f"search on {search['bird']} alone, the bird furthest from its limits at the "
              f"baseline, from {len(search['starts'])} starts, each ending at the first design "
              f"within its limits" + (f" that holds it longer than {beyond:.4f} s (the "
                                      f"baseline's worst hold)" if beyond is not None else "")
              + f", or at its budget; {search['simulations']} simulations in all, the last "
              f"of them the best start's design for every bird. No start reached that, so "
              f"the population's search did not run.")
    page.table([{"start": r["start_index"], "simulations": r["simulations"],
                 "within limits": r["within"], "failed runs": r["failed_runs"],
                 "jammed": r["jammed"], "force over a limit (N)": r["over_limit_N"],
                 "peak (N)": r["max_finger_force_N"], "finger": r["max_finger_force_finger"],
                 "hold (s)": r["hold_time_s"], **r["design"]} for r in search["starts"]],
               "Feasibility screen: where each start ended", "screen-table")


def search_table(page: Page, solver: dict) -> None:
    """The pattern search's simulations, in order: the step (scaled), the
    variable moved, the simulated hold and peak, and whether it was taken."""
    s = solver["search"]
    if answered(s):
        screen_table(page, s)
        return
    ruled = any(h.get("ruled_out_by") for h in solver["history"])
    birds = any("simulated_hold_times_s" in h for h in solver["history"])
    surveyed = [h for h in solver["history"] if h["move"] == "survey"]
    chosen = next((h for h in surveyed if h["accepted"]), None)
    page.text(f"Pattern search on the simulator (rtol {s['rtol']:g}): "
              + (f"first a survey of {len(surveyed)} points of a scrambled Sobol sequence in "
                 "the box, the search starting from "
                 + (f"the best of them (simulation {chosen['iteration']})" if chosen else
                    "the baseline (none of them beats it with a longer hold)") + "; then "
                 if surveyed else "")
              + f"steps from "
              f"{s['first_step']:g} down to {s['lattice']:g} of each variable's box, a move "
              f"taken when it lengthens the hold by more than {s['hold_band_s'] * 1e3:g} ms "
              f"with every finger under the cap; {s['simulations']} designs simulated, the "
              f"baseline's included"
              + (f", and {s['same_runs']} whose run would be one simulated before, scored "
                 "as that one (a belt that does not slow has no start or rate to act; a "
                 "finger the run never reached adds nothing to it)"
                 if s.get("same_runs") else "")
              + f", on a budget of {s['max_simulations']} designs from the start"
              + (", the survey's included" if surveyed else "")
              + ("" if s["lattice_optimum"] else ", the budget ending the search") + "."
              + ((f" {s['bird_simulations']} bird simulations: a candidate's birds are "
                  "simulated until one shows" if birds else " A candidate's run ends as soon "
                  "as it shows")
                 + " that it cannot beat the design the search stands at (a finger over its "
                   "limit, or a hold no longer than that design's); a run so ended gives no "
                   "hold or peak (—)." if ruled else ""))

    def ruled_out(h: dict) -> str:
        if not h.get("ruled_out_by"):
            return ""
        return (f"{h['ruled_out_by']}: " if birds else "") + (h.get("stopped")
                                                              or "its whole run")
    page.table([{"simulation": h["iteration"],
                 "step (scaled)": None if h["move"] == "survey" else h["radius"],
                 "variable": h["variable"], "move": h["move"],
                 "simulated hold (s)": None if h.get("stopped") else h["simulated_hold_time_s"],
                 "simulated peak (N)": None if h.get("stopped") else h["simulated_peak_force_N"],
                 **({"ruled out by": ruled_out(h)} if ruled else {}),
                 **({"run simulated before": h["same_run"]} if s.get("same_runs")
                    else {}),
                 "taken": h["accepted"]} for h in solver["history"]],
               "Pattern search", "history-table")


def multistart_section(page: Page, multistart: dict) -> None:
    """The starts and the distinct optima they reached."""
    page.section("Starts and local optima", "multistart")
    unverified = multistart["unverified_starts"]
    page.text(f"{len(multistart['starts'])} starts (the baseline and scrambled Sobol points, "
              f"seed {multistart['seed']}); one optimum: {multistart['same_optimum']}."
              + (f" Starts not verified: {', '.join(map(str, unverified))}." if unverified
                 else ""))
    page.table([{"optimum": i + 1, "verified hold (s)": o["verified_hold_time_s"],
                 "verified peak (N)": o["verified_max_finger_force_N"],
                 "starts": ", ".join(map(str, o["starts"])), **shown_design(o["design"])}
                for i, o in enumerate(multistart["optima"])],
               "Distinct verified optima, best first (angles in degrees)", "optima-table")
    page.table([shown_design(row) for row in multistart["starts"]],
               "Every start (angles in degrees)", "starts-table")


def shown_design(row: dict) -> dict:
    """A row holding a design's values by variable name, each in the unit a
    report shows (angles in degrees), the unit named; the other keys as they are."""
    out = {}
    for key, value in row.items():
        try:
            unit, k = shown(units(key))
        except KeyError:                       # not a variable
            out[key] = value
            continue
        out[key if unit == "1" else f"{key} ({unit})"] = k * value
    return out


def model_check_section(page: Page, check: dict) -> None:
    """Baseline and optimum simulated again with the spatial finger model."""
    page.section("The design on the spatial finger model", "model-check")
    h = check["hold_time_s"]
    page.text(f"The optimiser and its verification model the fingers as the thesis does "
              f"({check['design_model']}: bending in their own planes only). Baseline and "
              f"optimum were simulated again, the same scene with the fingers as rods "
              f"bending both ways ({check['finger_model']}, {check['contact_nodes']} "
              f"collocation intervals), with the cap's rule applied to that model's own "
              f"baseline peak. Hold: baseline {h['baseline']:.4f} s, optimum "
              f"{h['optimum']:.4f} s; "
              + ("the optimum's gain survives." if check["gain_survives"] else
                 "the optimum's gain does NOT survive: "
                 + ("its hold is shorter. " if not check["holds_at_least_as_long"] else "")
                 + ("it breaks the cap." if not check["within_cap"] else "")))
    page.table([{"bird": b["bird"], "design": label, "hold (s)": r["hold_time_s"],
                 "peak (N)": r["max_finger_force_N"], "peak finger": r["max_finger_force_finger"],
                 "cap (N)": b["cap_N"], "CPU (s)": r["cpu_time_s"]}
                for b in check["birds"] for label in ("baseline", "optimum")
                for r in [b[label]]], "Spatial finger model", "model-check-table")
    if check["model_warnings"]:
        page.text("Validity problems of the spatial runs: " + "; ".join(check["model_warnings"]))


def robustness_section(page: Page, robust: dict) -> None:
    """Baseline and optimum in the perturbed scenes (design/solvers/optimize/robustness.py)."""
    page.section("Robustness: what the problem does not know", "robustness")
    page.text(f"{robustness_text(robust)[0].upper()}{robustness_text(robust)[1:]} (target: "
              f"{robust['target_share']:.0%}). Each scene changes one thing the design problem "
              f"fixes; the optimum beats the baseline where it holds longer, stays under the "
              f"{robust['cap_N']:.2f} N cap and does not jam. Both designs run with the "
              f"{robust['model']['finger_model']} finger on the scene's own simulator (rtol "
              f"{robust['model']['rtol']:g}, steps up to {robust['model']['max_step_s']:g} s), "
              f"as design simulate runs it.")
    page.table([{"scene": r["case"],
                 "baseline hold (s)": r["baseline_hold_time_s"],
                 "optimum hold (s)": r["optimum_hold_time_s"],
                 "baseline peak (N)": r["baseline_max_finger_force_N"],
                 "optimum peak (N)": r["optimum_max_finger_force_N"],
                 "baseline jam": r["baseline_jam"] or "none",
                 "optimum jam": r["optimum_jam"] or "none",
                 "optimum beats baseline": r["optimum_beats_baseline"],
                 "why not": r["why_not"]}
                for r in robust["cases"]], "Baseline and optimum in perturbed scenes",
               "robustness-table")


def variable_rows(variables: list[dict]) -> list[dict]:
    """The variables table: bounds, baseline, optimum and change, angles in
    degrees (result.json keeps radians)."""
    rows = []
    for r in variables:
        unit, k = shown(r["unit"])
        rows.append({"variable": r["name"], "unit": unit,
                     **{key: k * r[key] for key in ("lower", "upper", "baseline", "optimum")},
                     "change": k * (r["optimum"] - r["baseline"]),
                     "active bound": r["active_bound"]})
    return rows


def design_page(result: dict, baseline: GraspRun, optimum: GraspRun) -> Page:
    """``baseline`` and ``optimum`` are the independent (fine) simulations."""
    page = Page(f"Design: {result['name']}")
    v, b = result["verification"], result["baseline"]
    ratio = v["hold_time_s"] / b["hold_time_s"] if b["hold_time_s"] > 0 else float("inf")
    status = result["status"]
    check = f" Then, {check_text(result['model_check'])}." if result.get("model_check") else ""
    if status == "no improvement found":
        page.banner(f"NO IMPROVEMENT FOUND: {result['message']} (hold {v['hold_time_s']:.4f} "
                    f"s, peak finger force {v['max_finger_force_N']:.2f} N, cap "
                    f"{v['cap_N']:.2f} N).", "neutral")
    elif status == "verified" and v.get("model_warnings"):
        page.banner(f"VERIFIED BY A MODEL OUTSIDE ITS VALIDITY: hold {v['hold_time_s']:.4f} s "
                    f"({ratio:.2f}x the baseline's {b['hold_time_s']:.4f} s), peak finger force "
                    f"{v['max_finger_force_N']:.2f} N under the {v['cap_N']:.2f} N cap; "
                    f"{'; '.join(v['model_warnings'])}.{check}", "failed")
    elif status == "verified":
        page.banner(f"VERIFIED: hold {v['hold_time_s']:.4f} s ({ratio:.2f}x the baseline's "
                    f"{b['hold_time_s']:.4f} s), peak finger force {v['max_finger_force_N']:.2f} N "
                    f"under the {v['cap_N']:.2f} N cap: {result['message']}.{check}",
                    "passed" if not check or result["model_check"]["gain_survives"] else "failed")
    else:
        page.banner(f"{status.upper()}: {result['message']}. Do not use this "
                    f"design without reading the verification table.{check}", "failed")
    page.section("The problem", "problem")
    page.text(result.get("description") or "")
    page.text(f"Maximise the longest interval in which the belt does not support the bird "
              f"(N = 0) with no finger pressing harder than {v['cap_N']:.2f} N "
              f"({result['cap']['given_as']}) at any instant. Caps: "
              f"{', '.join(result['problem']['caps'])}. Variables not listed keep the baseline's "
              f"value.")
    page.table(variable_rows(result["variables"]), "Decision variables (angles in degrees, "
               "the rest SI)", "variables-table")
    if result["rules_broken"]:
        page.text("Design rules broken: " + "; ".join(result["rules_broken"]))
    page.section("Verification", "verification")
    model = v.get("finger_model", result["objective"].get("finger_model", "planar"))
    page.text(f"The optimiser's hold comes from {result['objective']['source']} on a "
              f"{result['objective']['grid_step_s'] * 1e3:g} ms grid; the independent simulation "
              f"is the adaptive grasp simulator at 4x finer resolution. Both model the fingers "
              f"as {MODEL_WORDS.get(model, model)}.")
    page.table(verification_rows(result), "Optimiser against the independent simulation",
               "verification-table")
    page.table(summary_rows(baseline, "baseline") + summary_rows(optimum, "optimum"),
               "Baseline and optimum, both from the independent simulation", "summary-table")
    animation_section(page, result)
    grasp_figures(page, {"baseline": baseline, "optimum": optimum}, v["cap_N"])
    if result.get("model_check"):
        model_check_section(page, result["model_check"])
    if result.get("robustness"):
        robustness_section(page, result["robustness"])
    page.section("Optimiser convergence", "convergence")
    history = result["solver"]["history"]
    if result["solver"].get("method") == "pattern":
        search_table(page, result["solver"])
    else:
        page.table([{"outer iteration": h["iteration"], "trust region": h["radius"],
                     "NLP cap (N)": h.get("nlp_cap_N"),
                     "Ipopt status": h.get("ipopt_status", "error"),
                     "Ipopt iterations": h.get("ipopt_iterations"),
                     "NLP hold (s)": h.get("nlp_hold_time_s"),
                     "simulated hold (s)": h.get("simulated_hold_time_s"),
                     "simulated peak (N)": h.get("simulated_peak_force_N"),
                     "accepted": h.get("accepted", False)} for h in history],
                   "Trust-region iterations", "history-table")
    if any(h.get("history") for h in history):
        page.figure(convergence_figure(history), "convergence",
                    "Ipopt convergence: the NLP's hold time and its constraint violation")
    if result.get("profile"):
        profile_table(page, result["profile"])
    if result.get("population"):
        population_section(page, result["population"])
    if result.get("multistart"):
        multistart_section(page, result["multistart"])
    if result.get("pareto"):
        page.section("Hold time against the cap", "pareto")
        page.table(result["pareto"], "Pareto study", "pareto-table")
        page.figure(pareto_figure(result["pareto"], b), "pareto",
                    "Verified and optimiser hold time against the bruise cap")
    s = result["solver"]
    settings = [{"setting": k, "value": str(val)} for k, val in s["settings"].items()]
    settings += [{"setting": "Ipopt iterations (all)", "value": str(s["iterations"])},
                 {"setting": "NLP size", "value": str(s["nlp_size"])}]
    reproduce_section(page, result, settings, result["wall_time_s"])
    return page
