"""Where a design run's time goes (design/solvers/optimize/profile.py): the
profile in result.json and the report accounts for the run's wall time
phase by phase, sums CasADi's statistics of the NLPs that ran and records
peak memory.

One short ``design solve`` (the short test grasp on a 20 ms grid, one outer
iteration of at most 2 Ipopt iterations, then the fixed-design view: about
8 s at load 4 on 2 cores, half in building the two NLPs): every simulation is
the loop simulator's run of the short grasp, shared with test_reports.py
and test_design_solve.py (tests/design_cases.py), so the test pays for the
NLPs only once that run exists."""

from __future__ import annotations

import html
import json
import time
from pathlib import Path

import pytest

from design.cli import main
from design.solvers.optimize.profile import (IPOPT, OPTIMISER, UNACCOUNTED, VIEWS, Profile,
                                           profile_rows)
from tests import prefetch
from tests.design_cases import LOOP, shared_simulate_grasp, short_problem_file, short_setup


#: the prefetch worker's key for :func:`solve_profiled` (tests/prefetch.py)
PROFILED = "tests/test_profile.py: the short design solve's result and report"


@pytest.fixture(scope="module")
def solved(tmp_path_factory):
    """result.json and report.html of the short design solve, run ahead by
    the prefetch worker into the folder it was given, or here."""
    tmp = prefetch.folder(PROFILED, lambda: tmp_path_factory.mktemp("profile"))
    return prefetch.result(PROFILED, solve_profiled, tmp)


def solve_profiled(tmp: Path) -> tuple[dict, str]:
    """The short design solve in ``tmp``: its result.json and report.html."""
    run = shared_simulate_grasp(short_setup(), LOOP.simulator)
    path = short_problem_file(tmp / "problem.yaml",
                              {"groups.upper.stiffness_scale": [0.5, 1.5]},
                              max_iter=2, outer_iterations=1, time_step=0.02)
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr("design.solvers.optimize.trust_region.simulate_grasp",
                      lambda *args, **kwargs: run)
        main(["solve", str(path), "--out", str(tmp / "out"), "--quiet"])
    return (json.loads((tmp / "out" / "result.json").read_text()),
            (tmp / "out" / "report.html").read_text(encoding="utf-8"))


def test_phases_account_for_the_run(solved):
    profile = solved[0]["profile"]
    total = profile["wall_time_s"]
    phases = {p["phase"]: p for p in profile["phases"]}
    assert total > 0 and all(p["wall_time_s"] >= 0 and p["cpu_time_s"] >= 0
                             for p in phases.values())
    assert 0 < profile["cpu_time_s"]
    named = sum(p["wall_time_s"] for name, p in phases.items() if name != UNACCOUNTED)
    assert named <= total
    assert named >= 0.9 * total                             # little left unaccounted
    assert abs(named + phases[UNACCOUNTED]["wall_time_s"] - total) < 1e-9 * total + 1e-12
    assert total <= solved[0]["wall_time_s"] + 1.0           # the run's own clock
    for group in (OPTIMISER, VIEWS):
        assert phases[f"{group}: {IPOPT}"]["calls"] == 1
    assert phases["verification simulations (4x finer)"]["calls"] == 2
    assert profile["peak_memory_MiB"] > 0
    assert profile["machine"]["cpus"] >= 1 and len(profile["machine"]["load_average_at_start"]) == 3


def test_casadi_statistics_of_every_nlp_that_ran(solved):
    profile = solved[0]["profile"]
    phases = {p["phase"]: p["wall_time_s"] for p in profile["phases"]}
    for group in (OPTIMISER, VIEWS):
        n = profile["nlp"][group]
        assert n["solves"] == 1 and n["ipopt_iterations"] >= 1
        for name in ("nlp_f", "nlp_g", "nlp_grad_f", "nlp_jac_g"):
            calls = n["functions"][name]["calls"]
            assert isinstance(calls, int) and calls > 0
            assert n["functions"][name]["wall_time_s"] >= 0
            assert n["functions"][name]["cpu_time_s"] >= 0
        # the evaluations and Ipopt's own work are the Ipopt phase's wall time
        evaluations = sum(f["wall_time_s"] for f in n["functions"].values())
        assert evaluations <= n["ipopt_wall_time_s"] == phases[f"{group}: {IPOPT}"]
        assert n["ipopt_internal_wall_time_s"] == pytest.approx(
            n["ipopt_wall_time_s"] - evaluations, abs=1e-9)
        assert n["rootfinder_solves"] > 0


def test_the_report_shows_where_the_time_went(solved):
    result, page = solved
    assert 'id="profile-table"' in page and "Where the time went" in page
    names = [r["phase"] for r in profile_rows(result["profile"])]
    assert names[-2:] == [UNACCOUNTED, "total"]
    assert "↳ nlp_jac_g" in names
    assert all(html.escape(name) in page for name in names)


def test_a_phase_that_raises_is_still_timed_and_profiles_merge():
    a, b = Profile(), Profile()
    with pytest.raises(ValueError):
        with a.phase("x"):
            time.sleep(0.01)
            raise ValueError
    b.add("x", 1.0, 2)
    b.add_nlp(VIEWS, {"build_s": 0.5, "solve_s": 2.0, "post_s": 0.1, "finger_stages": 10,
                      "solve_cpu_s": 1.0,
                      "stats": {"iter_count": 3, "n_call_nlp_g": 4, "t_wall_nlp_g": 1.5,
                                "t_proc_nlp_g": 0.5, "n_call_nlp_jac_g": 1,
                                "t_wall_nlp_jac_g": 0.25, "t_proc_nlp_jac_g": 0.25,
                                "n_call_nlp_grad": 0, "t_wall_nlp_grad": 0.0}})
    b.add_nlp(OPTIMISER, None)                         # never built: nothing
    a.merge(b)
    assert a.phases["x"][0] >= 1.01 and a.phases["x"][1] == 3
    s = a.summary()["nlp"][VIEWS]
    assert s["functions"] == {"nlp_g": {"wall_time_s": 1.5, "cpu_time_s": 0.5, "calls": 4},
                              "nlp_jac_g": {"wall_time_s": 0.25, "cpu_time_s": 0.25,
                                            "calls": 1}}
    assert s["ipopt_internal_wall_time_s"] == pytest.approx(0.25)
    assert s["ipopt_internal_cpu_time_s"] == pytest.approx(0.25)
    assert s["rootfinder_solves"] == 50
    assert OPTIMISER not in a.summary()["nlp"]
