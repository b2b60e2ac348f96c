"""Robust design over a population of birds (design/solvers/optimize/population.py)
and the multistart's starts and optima (design/solvers/optimize/multistart.py).

The population NLP's invariant: birds that are the same bird under other
names must give the single bird's NLP solution, whatever the aggregate
(worst case: all epigraph rows active at one hold; weighted mean of equal
holds: that hold). Ipopt's path differs (more unknowns, the epigraph
variable), so the solutions agree to its tolerance, not to the bit: 1e-4
in the scaled design and 1e-4 s in hold, against the 0.36-0.67 s holds and
the [0, 1] box of the short grasp (tests/design_cases.py).
"""

import json
from dataclasses import replace

import numpy as np
import pytest

from design.io.scene import load_scene
from design.errors import ProblemFileError
from design.solvers.optimize.feasibility import (SIMULATIONS, STARTS, best_row, hardest_bird,
                                                  nearer)
from design.solvers.optimize.pattern_search import HOLD_BAND
from design.solvers.optimize.multistart import SAME_DESIGN, distinct_optima, starting_designs
from design.solvers.optimize.population import Member, Population, PopulationNLP
from design.solvers.optimize.transcription import NLPSettings
from design.run.solve import _verified, per_bird, population_comparison
from design.solvers.optimize.profile import Profile
from design.solvers.optimize.trust_region import Scored, verify
from tests import prefetch
from tests.design_cases import (LOOP, editable, sharing_simulations, short_problem_file,
                                single_bird_inputs, single_bird_optimum, stiffness_space)

NLP = NLPSettings(time_step=0.01, max_iter=60)


#: the prefetch worker's key for :func:`solve_twins` (tests/prefetch.py)
TWINS = "tests/test_population.py: the single bird's and the twins' NLPs"


def solve_twins() -> dict:
    """The single bird's NLP and the NLP of two copies of it, solved, with
    the twins' size and the cap rows after a rebound to [15, 16] N."""
    # a cap and box where the single NLP converges: at tighter caps or wider
    # boxes it stops at its iteration limit, and two unconverged solves need
    # not agree
    space, schedule, run, box = single_bird_inputs()
    alone = single_bird_optimum()
    population = Population((Member("twin-a", space), Member("twin-b", space)))
    nlp = PopulationNLP(population, [schedule, schedule], [run, run], [18.5, 18.5], NLP,
                        box=box)
    both = nlp.solve()
    size = nlp.size
    caps = nlp.rebound([15.0, 16.0], box).ubg[nlp._cap_rows]
    return {"alone": alone, "both": both, "size": size, "caps": caps,
            "per_bird": int(np.sum(nlp.nlps[0]._cap_rows))}


@pytest.fixture(scope="module")
def twins():
    return prefetch.result(TWINS, solve_twins)


def test_two_copies_of_a_bird_give_the_single_birds_design(twins):
    alone, both = twins["alone"], twins["both"]
    assert alone.success, alone.status
    assert both.success, both.status
    assert np.max(np.abs(both.d - alone.d)) < 1e-4
    assert abs(both.hold_time - alone.hold_time) < 1e-4
    assert np.allclose(both.peaks, alone.peak_force, rtol=1e-3)
    # one shared design, each bird's unknowns, the epigraph variable
    size = twins["size"]
    assert size["members"] == 2 and size["variables"] == 2 * alone.x.size - 2 + 1
    # rebound gives each bird its own cap rows
    caps, per_bird = twins["caps"], twins["per_bird"]
    assert np.all(caps[:per_bird] == 15.0) and np.all(caps[per_bird:] == 16.0)


def test_a_population_aggregates_its_holds():
    space = stiffness_space("upper")
    worst = Population((Member("a", space, 1.0), Member("b", space, 3.0)))
    mean = replace(worst, aggregate="mean")
    assert worst.hold([0.3, 0.5]) == 0.3
    assert mean.hold([0.3, 0.5]) == pytest.approx(0.25 * 0.3 + 0.75 * 0.5)
    assert Population.of(space).members[0].name == space.baseline.bird.name


def test_starting_designs_are_reproducible_and_fill_the_box():
    base = np.array([0.5, 0.2, 0.9])
    a, b = starting_designs(base, 8, 7), starting_designs(base, 8, 7)
    assert len(a) == 8 and np.array_equal(a[0], base)
    assert all(np.array_equal(x, y) for x, y in zip(a, b))
    points = np.array(a[1:])
    assert points.min() >= 0 and points.max() <= 1
    # scrambled Sobol (a (t, m, s)-net): every coordinate's halves hold 4 points each
    full = np.array(starting_designs(base, 9, 7)[1:])
    assert all(np.sum(full[:, j] < 0.5) == 4 for j in range(3))
    assert not np.array_equal(starting_designs(base, 8, 8)[1], a[1])
    assert len(starting_designs(base, 1, 0)) == 1


def test_optima_join_when_near_in_design_and_hold():
    e = SAME_DESIGN
    designs = [np.array([0.0, 0.0]), np.array([0.8 * e, 0.0]), np.array([1.6 * e, 0.0]),
               np.array([0.5, 0.5]), np.array([0.5, 0.5])]
    holds = [0.30, 0.301, 0.302, 0.40, 0.30]
    # 0-1-2 chain (each step within e, the ends 1.6 e apart); 3 and 4 share a
    # design but not a hold
    assert distinct_optima(designs, holds) == [[0, 1, 2], [3], [4]]


def test_population_input_errors_name_the_field(tmp_path):
    base = {"kind": "design", "scene": "problems/grasp_mean_bird_hard.yaml",
            "variables": {"groups.upper.stiffness_scale": [0.5, 2.0]}}
    bird = "models/birds/small_1_20kg.yaml"
    cases = [
        ({"birds": []}, "population.birds: expected a non-empty list"),
        ({"birds": [bird], "objective": "median"}, "population.objective"),
        ({"birds": [{"bird": bird, "weight": 0}]}, "population.birds[0].weight"),
        ({"birds": [bird, bird]}, "listed twice"),
        ({"birds": ["models/birds/no_such_bird.yaml"]}, "population.birds[0]"),
    ]
    for population, message in cases:
        with pytest.raises(ProblemFileError) as info:
            load_scene({**base, "population": population})
        assert message in str(info.value), (population, str(info.value))
    problem = load_scene({**base, "population": {"birds": [bird, {
        "bird": "models/birds/large_2_30kg.yaml", "weight": 2}]},
        "multistart": {"starts": 4, "seed": 3}})
    assert [b.mass for b in problem.population.birds] == [1.2, 2.3]
    assert problem.population.weights == (1.0, 2.0) and problem.population.objective == "worst"
    assert (problem.multistart.starts, problem.multistart.seed) == (4, 3)


def test_a_multistart_lists_its_distinct_optima_and_takes_the_best_verified():
    from design.io.design_problem import MultistartSpec
    from design.run.solve import _rank, multistart_summary

    def result(start, status, hold, d):
        return {"status": status, "message": f"start {start}: {status}", "start_index": start,
                "d": d, "design": {"groups.upper.stiffness_scale": 0.5 + d[0]},
                "verification": {"hold_time_s": hold, "max_finger_force_N": 20.0 + start}}

    results = {"s0": result(0, "verified", 0.30, [0.10]),
               "s1": result(1, "verified", 0.35, [0.70]),
               "s2": result(2, "verified", 0.351, [0.72]),
               "s3": result(3, "failed verification", 0.50, [0.40])}
    problem = type("P", (), {"multistart": MultistartSpec(4, 5)})()
    summary = multistart_summary(problem, None, list(results), results)
    assert [o["starts"] for o in summary["optima"]] == [[1, 2], [0]]     # best first
    assert summary["optima"][0]["verified_hold_time_s"] == 0.35
    assert summary["unverified_starts"] == [3] and summary["seed"] == 5
    # every start says how it ended, in its own words
    assert summary["starts"][3]["message"] == "start 3: failed verification"
    # an unverified longer hold never wins over a verified one
    assert max(results, key=lambda k: _rank(results[k])) == "s2"


def test_a_better_known_single_bird_design_is_named_not_adopted():
    """The single-bird optimum, verified on every bird, within every cap and
    longer for the population than the robust answer: the run says so (its
    message and closing line), and the answer stays the robust loop's."""
    from design.run.solve import NO_IMPROVEMENT, better_known, status_line

    comparison = {"objective": "worst",
                  "hold_time_s": {"baseline": 0.1792, "single_bird_optimum": 0.1945,
                                  "robust_optimum": 0.1792},
                  "within_caps": {"baseline": True, "single_bird_optimum": True,
                                  "robust_optimum": True}}
    note = better_known(comparison)
    assert "0.1945 s (worst) against 0.1792 s" in note
    over = {**comparison, "within_caps": {**comparison["within_caps"],
                                          "single_bird_optimum": False}}
    shorter = {**comparison, "hold_time_s": {**comparison["hold_time_s"],
                                             "single_bird_optimum": 0.17}}
    assert better_known(over) is None and better_known(shorter) is None
    result = {"status": NO_IMPROVEMENT, "baseline": {"hold_time_s": 0.1792},
              "verification": {"hold_time_s": 0.1792, "max_finger_force_N": 23.6,
                               "cap_N": 23.6},
              "population": {"better_known": note}}
    assert status_line(result).endswith(note)


def test_the_population_table_gives_each_designs_hold_peak_and_jam():
    """Per bird, the baseline's, the single-bird optimum's and the robust
    optimum's hold, peak and jam (its reasons, or ``none``), as simulated."""
    space = stiffness_space("lower", hi=2.0)
    with sharing_simulations():
        base = verify(space, space.scale(space.base_values), LOOP)
    robust = editable(base)
    reason = "the bird is still held off the belt when the run ends at 1.000 s (by 5b)"
    robust.members[0].run.summary["jam"] = [reason]
    single = {"holds_s": [0.25], "peaks_N": [17.5], "jams": ["none"], "cap_N": 20.0,
              "design": {}}
    table = population_comparison(space, Population.of(space), base, single, per_bird(robust),
                                  np.array([20.0]))
    row, = table["birds"]
    assert row["baseline_jam"] == ("; ".join(base.run.summary["jam"]) or "none")
    assert (row["single_bird_optimum_jam"], row["robust_optimum_jam"]) == ("none", reason)
    assert (row["single_bird_optimum_hold_time_s"], row["robust_optimum_hold_time_s"]) == \
        (0.25, base.hold)
    assert row["robust_optimum_max_finger_force_N"] == base.peak


def test_a_case_run_elsewhere_has_its_limiting_birds_run_simulated_again(monkeypatch):
    """A case a worker ran leaves every bird's hold, peak and jam in its
    result; this process simulates again only the bird whose run the
    report shows, the one with the shortest hold (here the second), at the
    case's design (the runs are deterministic: the case's own numbers)."""
    space = stiffness_space("lower", hi=2.0)
    population = Population((Member("a", space), Member("b", space), Member("c", space)))
    d = [0.25, 0.75]
    simulated = []
    monkeypatch.setattr("design.run.solve.verify", lambda birds, design, *args, **kwargs:
                        simulated.append((birds, list(design))) or "fine")
    result = {"holds_s": [0.3, 0.1, 0.2], "peaks_N": [1.0, 2.0, 3.0], "jams": ["none"] * 3,
              "d": d, "solver": {"search": {}}}
    assert _verified(population, "cap-1", result, LOOP, Profile(), None) == "fine"
    assert simulated == [(Population((population.members[1],)), d)]


def _two_birds(caps_scale=(1.5, 1.5)):
    """The short grasp's verified baseline as a population of two copies of
    its bird, and caps (N) of ``caps_scale`` times its peak."""
    space = stiffness_space("lower", hi=2.0)
    with sharing_simulations():
        base = verify(space, space.scale(space.base_values), LOOP)
    members = [base.members[0], editable(base).members[0]]
    two = Scored(base.d, members, Population((Member("a", space), Member("b", space))))
    return two, base.peak * np.asarray(caps_scale)


def test_a_populations_verification_names_its_birds_finger_model():
    """The population's verification says which finger model its birds ran
    (the closing line quotes it): a spatial scene's, not a default."""
    from design.solvers.optimize.trust_region import population_verdict

    two, caps = _two_birds()
    spatial = editable(two)
    for member in spatial.members:
        member.run.summary["finger_model"] = "spatial"
    claims = [(m.hold, "test") for m in spatial.members]
    assert population_verdict(spatial.population, claims, spatial, caps)["finger_model"] == \
        "spatial"


def test_the_screen_takes_the_bird_furthest_from_its_limits():
    """No screen where every bird keeps its limits; else the bird whose
    finger presses furthest over its cap, the first of equals, and a jammed
    bird before one that only presses too hard."""
    two, caps = _two_birds()
    assert hardest_bird(two, caps, 0.0) is None
    assert hardest_bird(two, caps * [1.0, 0.5], 0.0) == 1
    assert hardest_bird(two, caps * [0.5, 0.9], 0.0) == 0
    assert hardest_bird(two, caps * 0.5, 0.0) == 0
    two.members[1].run.summary["jam"] = ["the bird is still held off the belt when the run "
                                         "ends at 1.450 s (by 5b)"]
    assert hardest_bird(two, caps * [0.5, 1.0], 0.0) == 1


def test_the_screen_ranks_designs_by_their_distance_from_its_goal():
    """Fewest failed runs, then jams, then a hold beyond the baseline's
    worst, then the least force over a limit (none within them), then the
    longer hold; the first of equals. A design that keeps the bird within
    its limits by never lifting it is not nearer the goal than one that
    lifts it and presses too hard. Forces within 1 mN and holds within the
    search's band are equal."""
    def row(hold, failed=0, jammed=0, over=-1.0):
        return {"hold_time_s": hold, "failed_runs": failed, "jammed": jammed,
                "over_limit_N": over, "beyond_s": 0.05}
    rows = [row(0.5, jammed=1, over=1.0), row(0.4, over=30.0), row(0.3, over=12.0),
            row(0.0, failed=1, over=0.0), row(0.3, over=12.0)]
    assert best_row(rows) == 2
    never_lifted = row(0.0, over=-5.0)
    assert best_row(rows + [never_lifted]) == 2
    assert best_row(rows + [never_lifted, row(0.1), row(0.1)]) == 6
    assert best_row([{**r, "beyond_s": None} for r in rows + [never_lifted]]) == 5
    assert nearer((0, 0, False, 0.0, -0.10), (0, 0, False, 5e-4, -0.09))
    assert not nearer((0, 0, False, 0.0, -0.10), (0, 0, False, 5e-4, -0.10 + HOLD_BAND / 2))
    assert nearer((0, 0, False, 0.0, -0.10), (0, 0, False, 2e-3, -0.30))


def test_the_screen_searches_for_a_lifted_bird_within_its_limits(monkeypatch):
    """The screen's search prefers a design that lifts the bird and presses
    too hard to one that keeps the limits by never lifting it, and stops
    only at one that does both (its search and simulations faked: designs
    given by their hold and force over a limit)."""
    from types import SimpleNamespace

    from design.solvers.optimize import feasibility

    class Design:
        def __init__(self, hold, over):
            self.hold, self.over = hold, over

        def shortfall(self, cap, tolerance=0.0):
            return 0, 0, self.over

        def within(self, cap, tolerance=0.0):
            return self.over <= 0.0

    class Pool:
        def __init__(self, *args):
            pass

        def __enter__(self):
            return self

        def __exit__(self, *exc):
            return False

        def score(self, designs, incumbent=None):
            return [Design(0.0, -5.0) for _ in designs]

    seen = {}

    def compass(evaluate, start, first, beats, allowed, budget, enough, lattice):
        seen.update(beats=beats, enough=enough, lattice=lattice)
        return SimpleNamespace(d=start, value=first, trials=[])

    monkeypatch.setattr(feasibility, "Pairs", Pool)
    monkeypatch.setattr(feasibility, "compass", compass)
    monkeypatch.setattr(feasibility, "allowed_by", lambda space, rules: None)
    space = stiffness_space("lower")
    found = feasibility.screen(Population.of(space), 19.6, LOOP, None,
                               space.scale(space.base_values), 16, beyond=0.05)
    pressed, never_lifted, held = Design(0.09, 0.8), Design(0.0, -5.0), Design(0.09, -0.2)
    beats, enough = seen["beats"], seen["enough"]
    assert beats(pressed, never_lifted) and not beats(never_lifted, pressed)
    assert beats(held, pressed) and beats(Design(0.09, 0.5), pressed)
    assert [enough(d) for d in (pressed, never_lifted, held)] == [False, False, True]
    assert seen["lattice"] == LOOP.lattice
    assert (found.within, found.reached, found.simulations) == (True, False, 1)


def _population_problem(tmp_path, screen=None):
    path = short_problem_file(tmp_path / "p.yaml", {"groups.lower.stiffness_scale": [0.5, 2.0]})
    data = json.loads(path.read_text())
    data["population"] = {"birds": ["models/birds/small_1_20kg.yaml",
                                    "models/birds/large_2_30kg.yaml"],
                          **({"screen": screen} if screen else {})}
    return load_scene(data)


def test_a_baseline_that_breaks_a_birds_limits_is_screened_first(tmp_path):
    """The screen (its starts the baseline and Sobol points) is a case of its
    own, first; the baseline start's cap needs it; the single-bird
    comparison, which no case needs, comes last. A baseline within every
    bird's limits is not screened."""
    from design.run.solve import SCREEN, SINGLE_BIRD, design_cases

    problem = _population_problem(tmp_path, {"starts": 3, "max_simulations": 5})
    two, caps = _two_birds()
    space = two.population.space
    cases = design_cases(problem, space, two.population, [caps * [1.0, 0.5]], two)
    assert [c.key for c in cases] == [SCREEN, "cap-1", SINGLE_BIRD]
    screened, cap = cases[:2]
    assert cap.after == SCREEN and cap.inputs["screened"]
    assert screened.inputs["bird_index"] == 1 and screened.inputs["max_simulations"] == 5
    assert len(screened.inputs["starts"]) == 3
    assert screened.inputs["starts"][0] == space.scale(space.base_values).tolist()
    assert screened.inputs["cap_N"] == pytest.approx(caps[1] * 0.5)
    # the shortest hold is no longer than the screened bird's: it must beat the baseline's
    assert screened.inputs["beyond_s"] == two.hold
    plain = design_cases(problem, space, two.population, [caps], two)
    assert [c.key for c in plain] == ["cap-1", SINGLE_BIRD] and plain[0].after is None
    assert not plain[0].inputs["screened"]


def test_the_screened_cap_searches_from_the_first_start_that_reached_the_limits(
        tmp_path, monkeypatch):
    """A start within the hardest bird's limits starts the population's
    search (the first such start, anchored to the baseline); none, and the
    search is not run: the answer is the screen's best design."""
    from design.run import solve

    problem = _population_problem(tmp_path)
    calls = []
    monkeypatch.setattr(solve, "design_loop", lambda settings: lambda *a, **k: calls.append(
        ("search", a[4], k["anchor"])) or "searched")
    monkeypatch.setattr(solve, "unreached", lambda population, caps, settings, rows, bird:
                        calls.append(("unreached", [r["d"] for r in rows], bird)) or "nearest")
    row = {"bird": "large-bird-2.30kg", "reached": False, "d": [0.1]}
    rows = [row, {**row, "reached": True, "d": [0.7]}]
    assert solve._screened(problem, None, np.ones(2), {"rows": rows}, None) == "searched"
    assert calls[-1][0] == "search" and calls[-1][1].tolist() == [0.7] and calls[-1][2]
    missed = [row, {**row, "d": [0.7]}, {**row, "d": [0.9]}]
    assert solve._screened(problem, None, np.ones(2), {"rows": missed}, None) == "nearest"
    assert calls[-1] == ("unreached", [[0.1], [0.7], [0.9]], "large-bird-2.30kg")


def test_the_screen_tries_its_starts_in_turn_until_one_reaches_its_goal(tmp_path, monkeypatch):
    """The screen runs the starts in order and ends at the first that
    reaches its goal (the later ones cannot change where the population's
    search starts); where none reaches it, every start runs, and the case
    reports the nearest one's hold and peak."""
    from types import SimpleNamespace

    from design.run import solve
    from design.study.cases import Case

    problem = _population_problem(tmp_path)
    two, _ = _two_birds()
    tried = []

    def fake_screen(reaching):
        def run(bird, cap, settings, rules, start, budget, beyond):
            tried.append(start[0])
            k = int(start[0])
            value = SimpleNamespace(hold=0.1 * k, peak=30.0 - k)
            return SimpleNamespace(d=start, reached=k == reaching, row=lambda cap: {
                "d": start.tolist(), "reached": k == reaching, "failed_runs": 0, "jammed": 0,
                "over_limit_N": 0.0 if k == reaching else 10.0 - k, "hold_time_s": value.hold,
                "max_finger_force_N": value.peak})
        return run

    case = Case(solve.SCREEN, {"bird": "b", "bird_index": 1, "cap_N": 20.0,
                               "starts": [[0.0], [1.0], [2.0], [3.0]], "max_simulations": 4,
                               "beyond_s": None})
    monkeypatch.setattr(solve.DesignSpace, "design", lambda self, d: {"x": d[0]})
    monkeypatch.setattr(solve, "screen", fake_screen(reaching=1))
    result = solve._screen(problem, two.population, case)
    assert tried == [0.0, 1.0] and [r["start_index"] for r in result["rows"]] == [0, 1]
    assert result["rows"][-1]["reached"] and result["hold_time_s"] == pytest.approx(0.1)
    tried.clear()
    monkeypatch.setattr(solve, "screen", fake_screen(reaching=None))
    result = solve._screen(problem, two.population, case)
    assert tried == [0.0, 1.0, 2.0, 3.0] and not any(r["reached"] for r in result["rows"])
    # the nearest: the least force over a limit (start 3's 7 N)
    assert result["max_finger_force_N"] == 27.0


def test_screen_settings_are_read_and_checked(tmp_path):
    problem = _population_problem(tmp_path)
    assert (problem.population.screen_starts, problem.population.screen_simulations) == \
        (STARTS, SIMULATIONS)
    with pytest.raises(ProblemFileError, match="population.screen.starts"):
        _population_problem(tmp_path, {"starts": 0})
    with pytest.raises(ProblemFileError, match="population.screen.budget: unknown key"):
        _population_problem(tmp_path, {"budget": 3})


def test_an_unreached_screen_says_what_it_looked_for_and_where_each_start_ended():
    from design.run.solve import screen_diagnosis

    def row(start, hold, peak, within=False, jammed=0):
        return {"start_index": start, "hold_time_s": hold, "max_finger_force_N": peak,
                "within": within, "jammed": jammed, "simulations": 16, "beyond_s": 0.0}
    search = {"bird": "large-bird-2.30kg", "best": 1,
              "starts": [row(0, 0.44, 48.4, jammed=1), row(1, 0.0, 5.6, within=True),
                         row(2, 0.56, 76.9)]}
    text = screen_diagnosis(search, 19.6)
    assert text.startswith("no design found that keeps large-bird-2.30kg within its limits "
                           "(cap 19.60 N, fold forces, no jam) and holds it longer than the "
                           "baseline's worst hold, 0.0000 s")
    assert "from 3 starts (the baseline and 2 Sobol points), 48 designs" in text
    assert ("start 0: hold 0.4400 s, peak 48.40 N, jammed; start 1: hold 0.0000 s, peak "
            "5.60 N; start 2: hold 0.5600 s, peak 76.90 N, over a limit") in text
    assert text.endswith("the design reported is start 1's, verified for every bird")


def test_a_run_the_screen_answered_fails_even_where_its_design_verifies():
    """The screen's best design may keep every limit (a bird never lifted)
    and pass its verification: the run still fails, since no start held the
    hardest bird longer than the baseline, and says so."""
    from types import SimpleNamespace

    from design.run.solve import FAILED, _status

    row = {"start_index": 0, "hold_time_s": 0.0, "max_finger_force_N": 5.6, "within": True,
           "jammed": 0, "simulations": 16, "beyond_s": 0.0}
    best = SimpleNamespace()
    outcome = SimpleNamespace(claim=(0.0, "the screen"), errors=[], every_nlp_failed=False,
                              best=best, baseline=None, cap=19.6, caps=np.array([19.6]),
                              search={"method": "feasibility screen", "bird": "b", "best": 0,
                                      "starts": [row]})
    fine = SimpleNamespace(within=lambda caps, tolerance: True)
    status, message = _status(None, None, outcome, {"cap_tolerance": 0.01, "passed": True,
                                                    "model_warnings": []}, fine, [])
    assert status == FAILED and message.startswith("no design found that keeps b within")
