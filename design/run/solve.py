"""Running a design problem: optimise, verify, tabulate (``design solve``).

A run ends in one of four statuses (result.json's ``status``; the command's
exit status in brackets): ``verified`` (0), the independent simulation
confirms the optimiser's design; ``no improvement found`` (0), the loop
accepted no design and the baseline, which keeps the cap, is the answer;
``failed verification`` (1), the simulation disagrees with the optimiser or
the design breaks the cap; ``error`` (1), the optimiser could not work
(every NLP failed, or it could not evaluate its own design). Bad input (2)
and Ctrl-C (130) write no result.

result.json's ``profile`` says where the run's time went (wall time per
phase, Ipopt's function evaluations, peak memory: design/solvers/optimize/profile.py).
"""

from __future__ import annotations

import hashlib
import pickle
import time
from contextlib import nullcontext
from dataclasses import dataclass, field, replace
from functools import partial

import numpy as np

from design import __version__
from design.errors import StudyFailed
from design.io.design_problem import DesignProblem
from design.io.grasp_scene import GraspSettings
from design.io.scene_writer import grasp_spec, scene_yaml
from design.run import Progress, RunOutput
from design.run.animation import animation_record
from design.result import Status
from design.run.grasp import setup_of, timeseries
from design.solvers.grasp.simulation import simulate_grasp
from design.solvers.reproducible import numerics, one_blas_thread
from design.solvers.optimize import robustness
from design.solvers.optimize.robustness import robustness_text
from design.solvers.optimize.model_check import BASELINE, ModelCheck, check_text
from design.solvers.optimize.profile import (CASE_OVERHEAD, MODEL_CHECK, RESULT, ROBUSTNESS,
                                           SETUP, STUDY, VERIFICATION, Profile, clocks)
from design.solvers.optimize.feasibility import (answered, best_row, hardest_bird, screen,
                                                unreached, verification_budget)
from design.solvers.optimize.multistart import (SAME_DESIGN, SAME_HOLD, distinct_optima,
                                              starting_designs)
from design.solvers.optimize.pattern_search import search
from design.solvers.optimize.population import Member, Population
from design.solvers.optimize.transcription import rule_margins
from design.solvers.optimize.trust_region import (CAP_TOLERANCE, Outcome, Scored, caps_text,
                                                caps_value, certify, optimise,
                                                population_verdict, verify)
from design.solvers.optimize.variables import (DesignSpace, Variable, parameters_of,
                                             timed_conveyor)
from design.study.cases import FAILED as CASE_FAILED
from design.study.cases import Case, StudyOptions
from design.study.cluster import scheduler_address
from design.study.engine import run_study
from design.study.progress import StudyProgress

#: a scaled variable this close to 0 or 1 sits on its bound
ACTIVE = 1e-3
#: how a run ends; the first two are a success (exit status 0)
VERIFIED, NO_IMPROVEMENT = Status.VERIFIED, Status.NO_IMPROVEMENT
FAILED, ERROR = Status.FAILED_VERIFICATION, Status.ERROR


def design_space(problem: DesignProblem, progress: Progress | None = None) -> DesignSpace:
    """The problem's variables around its baseline grasp, the belt's
    deceleration timed (a position trigger becomes the time the baseline's
    bird reaches it)."""
    setup = setup_of(problem.scene)
    conveyor = setup.conveyor
    start = conveyor.start_time
    if conveyor.decelerates and start is None:
        if progress:
            progress("timing the belt's deceleration from a baseline simulation")
        run = simulate_grasp(setup, problem.settings.simulator, problem.settings.contact_nodes)
        slows = [t for t, name in run.trajectory.events if name == "belt slows"]
        start = slows[0] if slows else setup.duration
    setup = replace(setup, conveyor=timed_conveyor(conveyor, start))
    base = parameters_of(setup)
    return DesignSpace(setup, [Variable(n, lo, hi, base[n])
                               for n, (lo, hi) in problem.variables.items()])


def population_of_problem(problem: DesignProblem, space: DesignSpace) -> Population:
    """The birds the design must hold: the problem's population, each bird
    in the scene's grasp, or the scene's own bird alone."""
    spec = problem.population
    if spec is None:
        return Population.of(space)
    return Population(tuple(
        Member(bird.name, DesignSpace(replace(space.baseline, bird=bird), space.variables), w)
        for bird, w in zip(spec.birds, spec.weights)), spec.objective)


def run(problem: DesignProblem, progress: Progress | None = None,
        study: StudyOptions | None = None) -> RunOutput:
    """Optimise from every starting design for every cap (Pareto caps chained
    tightest first within a start), verify, and pick per cap the best
    verified design; a population also gets its single-bird comparison. The
    spatial model check and the robustness table's runs go to a background
    process (``check``).
    The cases run through design/study (``study``: where, and the case
    store); a study of one chain runs in this process. A throughput problem
    runs as design/run/line.py says. Every BLAS runs one
    thread (design/solvers/reproducible.py): the same answer on any machine."""
    if problem.objective == "throughput":
        from design.run import line
        return line.run(problem, progress, study)
    background = problem.model_check != "none" or problem.robustness
    with one_blas_thread(), ModelCheck(problem.settings.simulator) if background \
            else nullcontext() as check:
        return _run(problem, progress, study, check)


def _run(problem: DesignProblem, progress: Progress | None, study: StudyOptions | None,
         check: ModelCheck | None) -> RunOutput:
    t0 = time.perf_counter()
    profile = Profile()
    say = progress or (lambda message: None)
    with profile.phase(SETUP):
        space = design_space(problem, progress)
    population = population_of_problem(problem, space)
    settings = problem.settings
    d0 = space.scale(space.base_values)
    if problem.model_check != "none":
        check.submit(BASELINE, population, d0)
    if problem.robustness:
        submit_robustness(problem, space, check, ROBUST_BASELINE, d0)
    say("simulating the baseline at 4x the optimiser's resolution"
        + (f" for {len(population.members)} birds" if problem.population else ""))
    with profile.phase(VERIFICATION):
        baseline = verify(population, d0, settings)
    # one cap in newtons for every bird: ``baseline`` is the design bird's own peak
    reference = design_bird_peak(population, space, baseline, settings)
    caps = [np.full(len(population.members), c.resolve(reference)) for c in problem.caps]
    cases = design_cases(problem, space, population, caps, baseline)
    chains = sum(case.after is None for case in cases)
    options = study or StudyOptions(workers=1)
    if chains == 1:
        options = replace(options, workers=1, scheduler=None)
    local = options.workers == 1 and scheduler_address(options) is None
    kept = Kept() if local else None
    task = partial(solve_case, problem, progress if local and chains == 1 else None,
                   check if local else None, kept)
    # in this process the cases' own profiles and the engine's rest add up to
    # the study's time; on workers it is one phase of this process
    started = clocks()
    with nullcontext() if local else profile.phase(STUDY):
        results = run_study(cases, task, options=options, label=problem.name,
                            progress=None if chains == 1 else StudyProgress(quiet=progress is None),
                            problem_digest=problem_digest(problem))
    study = [now - then for now, then in zip(clocks(), started)]
    before = profile.timed()
    own = kept.profiles if kept else {}
    for key in results:
        if key in own:
            profile.merge(own[key])
    if local:
        cases_own = [now - then for now, then in zip(profile.timed(), before)]
        profile.add(CASE_OVERHEAD, max(study[0] - cases_own[0], 0.0), 1,
                    max(study[1] - cases_own[1], 0.0))
    output = _assemble(problem, space, population, cases, results, baseline, caps,
                       profile, t0, check, kept)
    output.result["profile"] = profile.summary()
    return output


def _assemble(problem: DesignProblem, space: DesignSpace, population: Population,
              cases: list[Case], results: dict, baseline: Scored, caps: list[np.ndarray],
              profile: Profile, t0: float, check: ModelCheck | None, kept: Kept | None
              ) -> RunOutput:
    """The run's output from its cases' results: per cap the best verified
    case, a multistart's optima, a population's comparison, the first cap's
    design on the spatial finger model (``check``). A failed case fails the
    run (:class:`StudyFailed`)."""
    settings = problem.settings
    failed = {k: r for k, r in results.items() if r["status"] in CASE_FAILED}
    if failed:
        raise StudyFailed("; ".join(f"case {k!r}: {r['status']}: {r.get('message', '')}"
                                    for k, r in failed.items()))
    entries = {}
    for k in range(len(caps)):
        keys = [case.key for case in cases if case.inputs.get("cap_index") == k]
        best = max(keys, key=lambda key: _rank(results[key]))
        entries[k] = {key: value for key, value in results[best].items()
                      if key not in ("d", *PER_BIRD)} | {"case": best}
        if entries[k]["status"] == NO_DESIGN:
            entries[k]["status"] = ERROR
        if problem.multistart.starts > 1:
            entries[k]["multistart"] = multistart_summary(problem, space, keys, results)
    primary = results[entries[0]["case"]]
    fine = _verified(population, entries[0]["case"], primary, settings, profile, kept)
    model_check, robust = None, None
    optimum = entries[0]["status"] in (VERIFIED, FAILED)        # else no optimum to check
    if problem.robustness and optimum:
        submit_robustness(problem, space, check, robust_optimum(entries[0]["case"]), fine.d)
    if problem.model_check != "none" and optimum:
        check.submit(entries[0]["case"], population, fine.d)
        with profile.phase(MODEL_CHECK):
            model_check = check.result(population, problem.caps[0],
                                       optimum=entries[0]["case"])
    if problem.robustness and optimum:
        with profile.phase(ROBUSTNESS):
            robust = robustness.table(check.runs(ROBUST_BASELINE),
                                      check.runs(robust_optimum(entries[0]["case"])),
                                      float(caps[0][0]))
    with profile.phase(RESULT):
        output = _output(problem, space, [entries[k] for k in range(len(caps))], fine,
                         baseline, t0, model_check)
    if robust is not None:
        output.result["robustness"] = robust
        output.tables["robustness.csv"] = robust["cases"]
    if problem.population:
        comparison = population_comparison(
            space, population, baseline, results[SINGLE_BIRD], primary, caps[0])
        search = entries[0]["solver"]["search"]
        if answered(search):
            comparison["robust_optimum_is"] = (
                f"the feasibility screen's best design for {search['bird']}: no start held "
                f"it within its limits longer than the baseline, and the population's "
                f"search did not run")
        note = better_known(comparison)
        if note:
            comparison["better_known"] = note
            output.result["message"] += f"; {note}"
        output.result["population"] = comparison
        output.tables["population.csv"] = comparison["birds"]
    if problem.multistart.starts > 1:
        output.tables["starts.csv"] = output.result["multistart"]["starts"]
    return output


#: a case's status when its design loop ended in ERROR
NO_DESIGN = "no design (optimiser error)"
#: the labels of the robustness table's background runs
ROBUST_BASELINE = "robustness: baseline"
#: the study's case for a population's single-bird comparison
SINGLE_BIRD = "single-bird"
#: the study's case for a population's feasibility screen
SCREEN = "screen"


@dataclass
class Kept:
    """What the cases a run ran in its own process leave beside their JSON
    results (the study engine returns JSON; the profile and the report need
    the objects): each case's profile and its 4x finer simulations."""

    profiles: dict[str, Profile] = field(default_factory=dict)
    fine: dict[str, Scored] = field(default_factory=dict)


def design_cases(problem: DesignProblem, space: DesignSpace, population: Population,
                 caps: list[np.ndarray], baseline: Scored) -> list[Case]:
    """Every start's chain of caps, tightest first (each design is feasible
    for the next, looser cap and warm-starts it, so that the hold cannot fall
    as the cap rises), and a population's single-bird comparison. Where the
    (verified) ``baseline`` breaks a bird's limits at the tightest cap, the
    feasibility screen comes first, one case trying its starts in turn: the
    baseline start's tightest cap needs it
    (design/solvers/optimize/feasibility.py)."""
    m = problem.multistart
    d0 = space.scale(space.base_values)
    starts = starting_designs(d0, m.starts, m.seed)
    order = sorted(range(len(caps)), key=lambda k: caps[k][0])
    cases, screened, single = [], [], []
    if problem.population:
        single.append(Case(SINGLE_BIRD, {"single_bird": space.baseline.bird.name,
                                         "cap_N": float(caps[0][0])}))
        b = hardest_bird(baseline, caps[order[0]], CAP_TOLERANCE)
        spec = problem.population
        if b is not None:
            # the shortest hold is no longer than this bird's: it must beat the baseline's
            beyond = baseline.hold if population.aggregate == "worst" else None
            screened.append(Case(SCREEN, {
                "bird": population.members[b].name, "bird_index": b,
                "starts": [d.tolist() for d in starting_designs(d0, spec.screen_starts, m.seed)],
                "cap_N": float(caps[order[0]][b]), "max_simulations": spec.screen_simulations,
                "beyond_s": beyond}))
    for s, d in enumerate(starts):
        after = SCREEN if s == 0 and screened else None
        for k in order:
            key = f"start-{s:02d}/cap-{k + 1}" if m.starts > 1 else f"cap-{k + 1}"
            cases.append(Case(key, {"start": d.tolist(), "start_index": s, "cap_index": k,
                                    "caps_N": caps[k].tolist(),
                                    "screened": after == SCREEN}, after))
            after = key
    # the screen first, as the tightest cap waits for it; the single-bird
    # comparison, which nothing waits for, last
    return screened + cases + single


def design_bird_peak(population: Population, space: DesignSpace, baseline: Scored,
                     settings) -> float:
    """The design bird's (the scene's own) baseline peak force (N): among the
    population's verified baseline runs, else verified alone."""
    names = [member.name for member in population.members]
    own = space.baseline.bird.name
    if own in names:
        return float(baseline.peaks[names.index(own)])
    return verify(Population.of(space), space.scale(space.base_values), settings).peak


def solve_case(problem: DesignProblem, progress: Progress | None, check: ModelCheck | None,
               kept: Kept | None, case: Case, upstream: dict | None) -> dict:
    """One case of :func:`design_cases`: the design loop from the case's
    start (or the upstream cap's optimum), its certification and its 4x
    finer verification; the result as result.json's entry for a cap, with
    the scaled design ``d``. ``check``: where the first cap's design starts
    its spatial runs, before its verification, and ``kept`` where it leaves
    its profile and simulations (this process's cases only)."""
    say = progress or (lambda message: None)
    space = design_space(problem)
    population = population_of_problem(problem, space)
    settings = problem.settings
    if case.key == SINGLE_BIRD:
        return _single_bird(problem, space, population, case, kept)
    if case.key == SCREEN:
        return _screen(problem, population, case)
    k = case.inputs["cap_index"]
    caps = np.array(case.inputs["caps_N"])
    say(f"cap {k + 1} of {len(problem.caps)}: {caps_text(caps)} "
        f"({problem.caps[k].describe()})")
    if case.inputs.get("screened"):
        outcome = _screened(problem, population, caps, upstream, progress)
    else:
        start = np.array(upstream["d"]) if upstream else np.array(case.inputs["start"])
        first = upstream is None and case.inputs["start_index"] == 0
        outcome = design_loop(settings)(population, caps, settings, problem.rules,
                                        None if first else start, progress,
                                        anchor=upstream is not None)
    certify(population, outcome, settings, problem.rules, progress)
    if check and k == 0 and problem.model_check != "none":
        check.submit(case.key, population, outcome.best.d)
    if check and k == 0 and problem.robustness and problem.multistart.starts == 1:
        submit_robustness(problem, space, check, robust_optimum(case.key), outcome.best.d)
    say("verifying at 4x finer resolution")
    with outcome.profile.phase(VERIFICATION):
        fine = verify(population, outcome.best.d, settings,
                      max_newton_solves=verification_budget(outcome.search))
    entry = _entry(space, problem, outcome, fine, problem.caps[k])
    if kept is not None:
        kept.profiles[case.key], kept.fine[case.key] = outcome.profile, fine
    v = entry["verification"]
    # a loop that could not work from this start is an answer, not a failed
    # case (the study engine's "error": the computation raised)
    status = NO_DESIGN if entry["status"] == ERROR else entry["status"]
    return {**entry, **per_bird(fine), "status": status, "d": outcome.best.d.tolist(),
            "start_index": case.inputs["start_index"],
            "hold_time_s": v["hold_time_s"],
            "max_finger_force_N": v["max_finger_force_N"],
            "verified": entry["status"] == VERIFIED}


def _single_bird(problem: DesignProblem, space: DesignSpace, population: Population,
                 case: Case, kept: Kept | None) -> dict:
    """The scene's own bird optimised alone at its cap, verified on every bird."""
    settings = problem.settings
    own = Population.of(space)
    cap = case.inputs["cap_N"]
    outcome = design_loop(settings)(own, cap, settings, problem.rules)
    fine = verify(population, outcome.best.d, settings)
    if kept is not None:
        kept.profiles[case.key] = outcome.profile
    return {"status": "done", "d": outcome.best.d.tolist(), "cap_N": float(cap),
            "design": space.design(outcome.best.d), **per_bird(fine), "hold_time_s": fine.hold}


def _screen(problem: DesignProblem, population: Population, case: Case) -> dict:
    """The feasibility screen: the pattern search on the hardest bird alone
    from each start in turn, each ended at the first design that reaches the
    screen's goal; the starts after the first that reaches it are not run
    (the population's search starts from that one). The result's ``rows``
    are the starts run; its hold and peak, the nearest one's."""
    inputs, b = case.inputs, case.inputs["bird_index"]
    bird = Population((population.members[b],))
    rows = []
    for s, start in enumerate(inputs["starts"]):
        found = screen(bird, inputs["cap_N"], problem.settings, problem.rules, np.array(start),
                       inputs["max_simulations"], inputs["beyond_s"])
        rows.append({"bird": inputs["bird"], "start_index": s, "beyond_s": inputs["beyond_s"],
                     **found.row(inputs["cap_N"]), "design": population.space.design(found.d)})
        if found.reached:
            break
    nearest = rows[best_row(rows)]
    return {"status": "done", "verified": False, "bird": inputs["bird"], "rows": rows,
            "hold_time_s": nearest["hold_time_s"],
            "max_finger_force_N": nearest["max_finger_force_N"]}


def _screened(problem: DesignProblem, population: Population, caps: np.ndarray,
              screened: dict, progress: Progress | None) -> Outcome:
    """The tightest cap's loop after the feasibility screen: from the design
    of the start that reached the screen's goal, else not run (the best
    start's design, with the screen's evidence)."""
    rows = screened["rows"]
    reached = [r for r in rows if r["reached"]]
    if not reached:
        (progress or (lambda message: None))(
            f"feasibility screen: no start held {rows[0]['bird']} within its limits")
        return unreached(population, caps, problem.settings, rows, rows[0]["bird"])
    return design_loop(problem.settings)(population, caps, problem.settings, problem.rules,
                                         np.array(reached[0]["d"]), progress, anchor=True)


def per_bird(scored: Scored) -> dict:
    """Each bird's hold (s), peak (N) and jam, in member order, as a case's
    result carries them (:data:`PER_BIRD`)."""
    return dict(zip(PER_BIRD, (scored.holds.tolist(), scored.peaks.tolist(), jams(scored))))


#: the keys of :func:`per_bird`
PER_BIRD = ("holds_s", "peaks_N", "jams")


def jams(scored: Scored) -> list[str]:
    """Each bird's jam: why its grasp is a jam ("; "-joined), ``none``, or
    why its run ended early."""
    return ["; ".join(m.run.summary["jam"]) or
            ("none" if m.run.summary["ok"] else f"run ended early: {m.run.summary['message']}")
            for m in scored.members]


def design_loop(settings):
    """The loop the problem names (``solver: {method: ..}``)."""
    return search if settings.method == "pattern" else optimise


def _rank(result: dict) -> tuple:
    """Order of a cap's results: verified first, then the longer verified
    hold; the baseline start's first among the unverified."""
    return (result["status"] == VERIFIED, result["verification"]["hold_time_s"]
            if result["status"] == VERIFIED else 0.0)


def _verified(population: Population, key: str, result: dict, settings, profile: Profile,
              kept: Kept | None) -> Scored:
    """The 4x finer simulations of a case's design: the case's own if it
    ran in this process, else its limiting bird's (the report's run)
    simulated again (deterministic: the same run); every bird's numbers are
    in the case's result (:func:`per_bird`)."""
    fine = kept.fine.get(key) if kept else None
    if fine is None:
        limiting = population.members[int(np.argmin(result["holds_s"]))]
        with profile.phase(VERIFICATION):
            fine = verify(Population((limiting,), population.aggregate), np.array(result["d"]),
                          settings, max_newton_solves=
                          verification_budget(result["solver"]["search"]))
    return fine


def multistart_summary(problem: DesignProblem, space: DesignSpace, keys: list[str],
                       results: dict) -> dict:
    """The starts of one cap and the distinct optima they reached
    (design/solvers/optimize/multistart.py says when two are one)."""
    rows = [{"start": results[key].get("start_index", i), "case": key,
             "status": results[key]["status"], "message": results[key]["message"],
             "verified_hold_time_s": results[key]["verification"]["hold_time_s"],
             "verified_max_finger_force_N": results[key]["verification"]["max_finger_force_N"],
             **results[key]["design"]} for i, key in enumerate(keys)]
    verified = [i for i, key in enumerate(keys) if results[key]["status"] == VERIFIED]
    groups = distinct_optima([np.asarray(results[keys[i]]["d"]) for i in verified],
                             [rows[i]["verified_hold_time_s"] for i in verified])
    optima = sorted(({"verified_hold_time_s": rows[verified[g[0]]]["verified_hold_time_s"],
                      "verified_max_finger_force_N":
                          rows[verified[g[0]]]["verified_max_finger_force_N"],
                      "design": results[keys[verified[g[0]]]]["design"],
                      "starts": [rows[verified[i]]["start"] for i in g]} for g in groups),
                    key=lambda o: -o["verified_hold_time_s"])
    return {"starts": rows, "optima": optima, "seed": problem.multistart.seed,
            "same_optimum": f"verified designs within {SAME_DESIGN} in every scaled variable "
                            f"and {100 * SAME_HOLD:g} % in hold, joined transitively",
            "unverified_starts": [r["start"] for i, r in enumerate(rows) if i not in verified]}


def population_comparison(space: DesignSpace, population: Population, baseline: Scored,
                          single: dict, robust: dict, caps: np.ndarray) -> dict:
    """Each bird's hold, peak and jam under the baseline, the single-bird
    optimum (the scene's own bird alone, at its cap) and the robust optimum
    (their cases' :func:`per_bird`), all verified at 4x the optimiser's
    resolution."""
    each = {"baseline": per_bird(baseline), "single_bird_optimum": single,
            "robust_optimum": robust}
    designs = {label: (np.array(r["holds_s"]), np.array(r["peaks_N"]))
               for label, r in each.items()}
    jammed = {label: r["jams"] for label, r in each.items()}
    rows = [{"bird": member.name, "weight": float(population.weights[b]),
             "cap_N": float(caps[b]),
             **{f"{label}_{key}": float(values[i][b]) for label, values in designs.items()
                for i, key in enumerate(("hold_time_s", "max_finger_force_N"))},
             **{f"{label}_jam": jammed[label][b] for label in designs}}
            for b, member in enumerate(population.members)]
    return {"objective": population.aggregate, "single_bird": space.baseline.bird.name,
            "single_bird_cap_N": single["cap_N"], "single_bird_design": single["design"],
            "hold_time_s": {label: population.hold(holds)
                            for label, (holds, _) in designs.items()},
            "limiting_bird": {label: population.members[int(np.argmin(holds))].name
                              for label, (holds, _) in designs.items()},
            "within_caps": {label: bool(np.all(peaks <= caps * (1 + CAP_TOLERANCE)))
                            for label, (_, peaks) in designs.items()},
            "birds": rows}


def better_known(comparison: dict) -> str | None:
    """Where the single-bird optimum, verified on every bird at 4x finer
    resolution with every bird under its cap, holds the population longer
    than the robust answer: a sentence that says so. The robust answer
    stands: a design is certified only where the population's NLP
    reproduces it, and started from this design the robust loop's
    fixed-design NLP need not converge."""
    hold, within = comparison["hold_time_s"], comparison["within_caps"]
    single, robust = hold["single_bird_optimum"], hold["robust_optimum"]
    if not within["single_bird_optimum"] or single <= robust:
        return None
    return (f"a better design is known: the single-bird optimum holds the population "
            f"{single:.4f} s ({comparison['objective']}) against {robust:.4f} s, every bird "
            f"under its cap at 4x finer resolution; the robust loop did not reach it, so the "
            f"population's NLP has not certified it (result.json: population."
            f"single_bird_design)")


def problem_digest(problem: DesignProblem) -> str:
    """A hash of the parsed problem: a case store belongs to one problem."""
    return hashlib.sha256(pickle.dumps((problem, __version__))).hexdigest()[:16]


def _output(problem: DesignProblem, space: DesignSpace, entries: list[dict], fine: Scored,
            baseline: Scored, t0: float, model_check: dict | None) -> RunOutput:
    """The run's result, tables and files; the first cap's entry is the
    primary one (its design, verified as ``fine``, is reported)."""
    primary = entries[0]
    status, message = overall_status(entries)
    result = {
        "kind": "design", "name": problem.name, "toolkit_version": __version__,
        "units": {"length": "m", "force": "N", "angle": "rad", "time": "s",
                  "speed": "m/s", "acceleration": "m/s^2", "drum_speed": "rad/s"},
        "description": problem.description,
        "problem": {"variables": {v.name: {"lower": v.lo, "upper": v.hi, "baseline": v.baseline,
                                           "unit": v.unit} for v in space.variables},
                    "caps": [c.describe() for c in problem.caps],
                    "rules": vars(problem.rules)},
        **primary, "status": status, "message": message,
        "baseline": {"hold_time_s": baseline.hold,
                     "hold_windows": baseline.run.summary["hold_windows"],
                     "max_finger_force_N": baseline.peak,
                     "max_finger_force_finger": baseline.run.summary["max_finger_force_finger"],
                     "design": {v.name: v.baseline for v in space.variables}},
        "model_check": model_check,
        "numerics": numerics(),
        "wall_time_s": time.perf_counter() - t0,
    }
    if problem.pareto:
        result["pareto"] = sorted((_pareto_row(e) for e in entries), key=lambda r: r["cap_N"])
    rows = {"baseline": timeseries(baseline.run), "optimum": timeseries(fine.run)}
    result["animation"] = animation_record(
        {label: (grasp_spec(run.setup, GraspSettings(problem.settings.simulator,
                                                     problem.settings.contact_nodes),
                            f"{problem.name}_{label}", ""), rows[label])
         for label, run in (("baseline", baseline.run), ("optimum", fine.run))},
        primary["verification"]["cap_N"])
    tables = {"design.csv": primary["variables"], "timeseries.csv": rows["optimum"]}
    if problem.pareto:
        tables["pareto.csv"] = result["pareto"]
    files = {}
    if primary["status"] in (VERIFIED, FAILED):        # else the baseline: no optimum
        spec = grasp_spec(space.setup(fine.d), problem.scene.settings,
                          f"{problem.name}_optimum",
                          f"Optimised by design solve from {problem.name} (cap "
                          f"{primary['verification']['cap_N']:.3g} N).")
        files["optimum.yaml"] = scene_yaml(spec)
    return RunOutput(result, tables, ok=status in (VERIFIED, NO_IMPROVEMENT), files=files,
                     artifacts={"baseline": baseline.run, "optimum": fine.run})


def overall_status(entries: list[dict]) -> tuple[str, str]:
    """The run's status and message: the first cap's (whose design the
    result reports), unless another cap ended in an error or failed."""
    worst = next((s for s in (ERROR, FAILED) if s in [e["status"] for e in entries]),
                 entries[0]["status"])
    entry = next(e for e in entries if e["status"] == worst)
    if entry is entries[0]:
        return worst, entry["message"]
    return worst, f"cap {entry['cap']['N']:.2f} N: {entry['message']}"


def status_line(result: dict) -> str:
    """The command's closing line for a design result: its status and numbers."""
    v, b, status = result["verification"], result["baseline"], result["status"]
    peak = f"peak finger force {v['max_finger_force_N']:.2f} N (cap {v['cap_N']:.2f} N)"
    if status == ERROR:
        return f"error: {result['message']}"
    if "line" in result:
        return f"{status}: {result['message']}"
    if status == NO_IMPROVEMENT:
        known = result.get("population", {}).get("better_known")
        return (f"no improvement found: the design is the baseline, unchanged; hold "
                f"{v['hold_time_s']:.4f} s, {peak}" + (f"; {known}" if known else ""))
    caveat = " (by a model outside its validity)" if status == VERIFIED and \
        v["model_warnings"] else ""
    check = f"; {check_text(result['model_check'])}" if result.get("model_check") else ""
    if result.get("robustness"):
        check += f"; {robustness_text(result['robustness'])}"
    claimed = result["objective"]["hold_time_s"]
    claimed = "not evaluated" if claimed is None or not np.isfinite(claimed) else \
        f"{claimed:.4f} s"
    return (f"{status}{caveat}: hold {v['hold_time_s']:.4f} s in the independent simulation "
            f"with {v['finger_model']} fingers (optimiser {claimed}; baseline "
            f"{b['hold_time_s']:.4f} s), "
            f"{peak}{check}")


def _entry(space: DesignSpace, problem: DesignProblem, outcome: Outcome, fine: Scored,
           cap_spec) -> dict:
    best, view, claim = outcome.best, outcome.final, outcome.claim
    claimed, source = claim
    check = population_verdict(best.population, outcome.claims, fine, outcome.caps)
    d = best.d
    variables = [{"name": v.name, "unit": v.unit, "lower": v.lo, "upper": v.hi,
                  "baseline": v.baseline, "optimum": v.lo + d[i] * (v.hi - v.lo),
                  "active_bound": "lower" if d[i] < ACTIVE else "upper" if d[i] > 1 - ACTIVE
                  else ""} for i, v in enumerate(space.variables)]
    status, message = _status(space, problem, outcome, check, fine, variables)
    iterations = outcome.iterations
    return {
        "status": status, "message": message,
        "design": {v["name"]: v["optimum"] for v in variables},
        "variables": variables,
        "objective": {"hold_time_s": claimed, "source": source,
                      "grid_step_s": problem.settings.nlp.time_step,
                      "finger_model": space.baseline.finger_model},
        "verification": check,
        "cap": {"N": caps_value(outcome.caps), "given_as": cap_spec.describe()},
        "rules_broken": [tag for margin, tag in rule_margins(space.values(np.asarray(d, float)),
                                                             space.baseline, problem.rules)
                         if margin < -1e-9],
        "solver": {
            "method": problem.settings.method, "search": outcome.search,
            "ipopt_status": outcome.nlp.status if outcome.nlp else
            (iterations[-1].get("ipopt_status", "not run") if iterations else "not run"),
            "iterations": int(sum(i.get("ipopt_iterations", 0) for i in iterations)),
            "outer_iterations": len(iterations),
            "wall_time_s": outcome.wall_time,
            "nlp_size": next((i["nlp_size"] for i in reversed(iterations) if "nlp_size" in i),
                             None if view is None else view.size),
            "final_nlp": None if view is None else {
                "ipopt_status": view.status, "iterations": view.iterations,
                "wall_time_s": view.wall_time,
                "constraint_violation": view.violation if view.history else None,
                "iteration_returned": view.iteration},
            "history": iterations,
            "settings": {"time_step_s": problem.settings.nlp.time_step,
                         "beam_intervals": problem.settings.nlp.beam_intervals,
                         "max_iter": problem.settings.nlp.max_iter,
                         "outer_iterations": problem.settings.outer_iterations,
                         "trust_region": problem.settings.radius,
                         "cap_margin": problem.settings.cap_margin,
                         "ipopt": problem.settings.nlp.ipopt},
        },
    }


def _status(space, problem, outcome: Outcome, check, fine: Scored, variables
            ) -> tuple[str, str]:
    """One cap's status (see the module's docstring) and why."""
    claimed, source = outcome.claim
    errors = outcome.errors
    failures = f" ({len(errors)} NLP failure(s): {'; '.join(errors)})" if errors else ""
    keeps_cap = fine.within(outcome.caps, check["cap_tolerance"])
    if outcome.every_nlp_failed:
        start = "baseline" if outcome.best is outcome.baseline else "starting design"
        return ERROR, ("every NLP of the design loop failed, so no design was tried; the "
                       f"{start} is unchanged and not an answer: " + "; ".join(errors))
    if outcome.best is outcome.baseline and keeps_cap:
        return NO_IMPROVEMENT, ("the design loop found no design that holds longer under "
                                "the cap; the design reported is the baseline, unchanged"
                                + failures)
    if answered(outcome.search):
        return FAILED, screen_diagnosis(outcome.search, outcome.cap)
    if check["passed"] and check["model_warnings"]:
        return VERIFIED, ("verified by a model outside its validity: the independent "
                          "simulation confirms the design, but the grasp model is outside "
                          "its validity: " + "; ".join(check["model_warnings"]))
    if check["passed"]:
        return VERIFIED, "the independent simulation confirms the design"
    if not np.isfinite(claimed):
        return FAILED, (f"the optimiser could not evaluate its own design ({source}), so the "
                        f"independent simulation has no claim to confirm{failures}")
    if not outcome.feasible:
        return FAILED, "infeasible: " + _diagnosis(space, problem, outcome, variables)
    return FAILED, (f"the independent simulation disagrees: hold {fine.hold:.4f} s against the "
                    f"optimiser's {claimed:.4f} s, peak {check['max_finger_force_N']:.2f} N "
                    f"against the cap {check['cap_N']:.2f} N")


def _diagnosis(space, problem, outcome: Outcome, variables) -> str:
    """Why no design met the cap: the lowest peak reached and what stopped it."""
    best = outcome.best
    k = int(np.argmax(best.peaks / outcome.caps))
    cap, run = outcome.caps[k], best.members[k].run
    bird = f" on {best.population.members[k].name}" if len(outcome.caps) > 1 else ""
    bounds = [f"{v['name']} at its {v['active_bound']} bound" for v in variables
              if v["active_bound"]]
    values = space.values(np.asarray(best.d, float))
    rules = [tag for margin, tag in rule_margins(values, space.baseline, problem.rules)
             if margin < 1e-6]
    stops = bounds + rules
    return (f"no design within the bounds keeps every finger under {cap:.2f} N{bird}: the "
            f"smallest peak force reached is {best.peaks[k]:.2f} N (finger "
            f"{run.summary['max_finger_force_finger']}); "
            + ("active: " + ", ".join(stops) if stops else
               "no bound or rule is active: the trust-region loop stopped at a local optimum"))


def screen_diagnosis(search: dict, cap: float) -> str:
    """Why the population's search did not run: what the feasibility
    screen looked for and where each of its starts ended."""
    rows = search["starts"]
    beyond = rows[0].get("beyond_s")
    goal = f" and holds it longer than the baseline's worst hold, {beyond:.4f} s" \
        if beyond is not None else ""
    ends = "; ".join(
        f"start {r['start_index']}: hold {r['hold_time_s']:.4f} s, peak "
        f"{r['max_finger_force_N']:.2f} N" + ("" if r["within"] else
                                               ", jammed" if r["jammed"] else ", over a limit")
        for r in rows)
    return (f"no design found that keeps {search['bird']} within its limits (cap {cap:.2f} N, "
            f"fold forces, no jam){goal}, so none holds the population better than the "
            f"baseline: the feasibility screen's pattern search on that bird alone from "
            f"{len(rows)} starts (the baseline and {len(rows) - 1} Sobol points), "
            f"{sum(r['simulations'] for r in rows)} designs, each start's best: {ends}; the "
            f"design reported is start {rows[search['best']]['start_index']}'s, verified for "
            f"every bird")


def _pareto_row(entry: dict) -> dict:
    v = entry["verification"]
    return {"cap_N": v["cap_N"], "status": entry["status"],
            "optimiser_hold_time_s": entry["objective"]["hold_time_s"],
            "verified_hold_time_s": v["hold_time_s"],
            "verified_max_finger_force_N": v["max_finger_force_N"], "passed": v["passed"]}


def robust_optimum(key: str) -> str:
    """The background runs' label for case ``key``'s design's robustness scenes."""
    return f"robustness: optimum of {key}"


def submit_robustness(problem: DesignProblem, space: DesignSpace, check: ModelCheck,
                      label: str, d: np.ndarray) -> None:
    """Queue the robustness scenes of the scaled design ``d`` as ``label``
    (once), on the scene's own simulator (robustness.simulator)."""
    check.submit_setups(label, robustness.scenes(space.setup(d)),
                        robustness.simulator(problem.scene.settings.integrator))
