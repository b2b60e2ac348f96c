"""How a design run ends when its optimiser fails or finds nothing: every NLP
failing is an error (exit 1), never the baseline reported as verified; a
loop that improves nothing says so (exit 0, the baseline labelled as such).

The loop's decisions are under test, not the physics: every design
simulates to one run of the short test grasp (tests/design_cases.py)."""

import json

import numpy as np
import pytest

from design.cli import main
from design.run.solve import ERROR, FAILED, NO_IMPROVEMENT, VERIFIED, overall_status
from design.solvers.optimize.transcription import DesignNLP, NLPResult
from tests.design_cases import shared_simulate_grasp, short_problem_file, short_setup


@pytest.fixture(scope="module")
def one_run():
    return shared_simulate_grasp(short_setup())         # also test_interrupt.py's


@pytest.fixture
def problem(tmp_path, one_run, monkeypatch):
    """A design problem on the short grasp whose every simulation is ``one_run``."""
    monkeypatch.setattr("design.solvers.optimize.trust_region.simulate_grasp",
                        lambda *args, **kwargs: one_run)
    return short_problem_file(tmp_path / "problem.yaml",
                              {"groups.lower.stiffness_scale": [0.5, 2.0]},
                              max_iter=5, outer_iterations=2)


def solve(problem, capsys):
    out = problem.parent / "out"
    code = main(["solve", str(problem), "--out", str(out), "--quiet"])
    stdout, stderr = capsys.readouterr()
    result = json.loads((out / "result.json").read_text())
    report = (out / "report.html").read_text(encoding="utf-8")
    return code, result, stdout.strip().splitlines()[-1], stderr, report, out


class NoBetterNLP:
    """An NLP that converges to the middle of its box: its design simulates
    to the baseline's run, so no candidate holds longer."""

    def __init__(self, space, schedule, run, cap, settings, rules=None, box=None,
                 progress=None, objective="hold"):
        self.d = (np.asarray(box[0], float) + np.asarray(box[1], float)) / 2
        self.hold = run.summary["hold_time_s"]

    def rebound(self, cap, box=None):
        """The loop's NLP after a rejected candidate (DesignNLP.rebound)."""
        self.d = (np.asarray(box[0], float) + np.asarray(box[1], float)) / 2
        return self

    def solve(self):
        history = [{"iteration": 0, "hold_time_s": self.hold, "violation": 0.0}]
        return NLPResult(self.d, np.zeros(1), self.hold, 0.0, "Solve_Succeeded", True, 1,
                         0.0, {"variables": 1}, history, self.d, np.zeros(0), np.zeros(0))


class IpoptEndsOnAnError:
    """Ipopt as CasADi returns it when an evaluation threw (as an
    interrupted solve can end)."""

    def __init__(self, *args, **kwargs):
        pass

    def __call__(self, x0, **bounds):
        return {"x": x0, "lam_g": 0.0, "lam_x": 0.0}

    def stats(self):
        return {"return_status": "NonIpopt_Exception_Thrown", "iter_count": 3,
                "success": False}


def failing_nlps(how):
    """Every design-moving NLP fails (``how``); the optimiser's view of a
    fixed design works, so the baseline would verify (the reported bug)."""
    def nlp(*args, objective="hold", **kwargs):
        if objective == "track":
            return NoBetterNLP(*args, **kwargs)
        if how == "raises":
            raise RuntimeError("the NLP cannot be built here")
        return DesignNLP(*args, **kwargs)
    return nlp


@pytest.mark.parametrize("how", ["raises", "Ipopt error status"])
def test_every_nlp_failing_is_an_error_not_a_verified_baseline(problem, monkeypatch, capsys,
                                                                how):
    monkeypatch.setattr("design.solvers.optimize.trust_region.DesignNLP", failing_nlps(how))
    monkeypatch.setattr("design.solvers.optimize.transcription.ca.nlpsol", IpoptEndsOnAnError)
    code, result, last, stderr, report, out = solve(problem, capsys)
    assert code == 1
    assert result["status"] == ERROR
    assert result["message"].startswith("every NLP of the design loop failed")
    assert len(result["solver"]["history"]) == 2
    assert all("error" in i for i in result["solver"]["history"])
    expected = "cannot be built" if how == "raises" else "NonIpopt_Exception_Thrown"
    assert expected in result["message"]
    assert last.startswith("error: every NLP") and "FAILED: error" in stderr
    assert '<div class="banner failed" id="verdict">ERROR: every NLP' in report
    assert not (out / "optimum.yaml").exists()          # the baseline is no optimum


def test_no_improvement_is_its_own_status_with_the_baseline_labelled(problem, monkeypatch,
                                                                     capsys):
    monkeypatch.setattr("design.solvers.optimize.trust_region.DesignNLP", NoBetterNLP)
    code, result, last, stderr, report, out = solve(problem, capsys)
    assert code == 0
    assert result["status"] == NO_IMPROVEMENT
    assert result["design"] == result["baseline"]["design"]
    assert [i["accepted"] for i in result["solver"]["history"]] == [False, False]
    assert last.startswith("no improvement found: the design is the baseline, unchanged")
    assert "FAILED" not in stderr
    assert '<div class="banner neutral" id="verdict">NO IMPROVEMENT FOUND' in report
    assert not (out / "optimum.yaml").exists()


def entry(status, cap):
    return {"status": status, "message": f"{status} at {cap}", "cap": {"N": cap}}


def test_a_pareto_run_reports_its_worst_cap():
    """The first cap's status unless another cap ended in an error or failed."""
    assert overall_status([entry(VERIFIED, 20.0), entry(NO_IMPROVEMENT, 30.0)]) == \
        (VERIFIED, "verified at 20.0")
    assert overall_status([entry(NO_IMPROVEMENT, 20.0), entry(VERIFIED, 30.0)]) == \
        (NO_IMPROVEMENT, "no improvement found at 20.0")
    assert overall_status([entry(VERIFIED, 20.0), entry(FAILED, 30.0),
                           entry(ERROR, 40.0)]) == (ERROR, "cap 40.00 N: error at 40.0")


def test_a_claim_the_optimiser_cannot_evaluate_fails_verification_with_a_report(
        problem, monkeypatch, capsys):
    """A design off the baseline whose fixed-design NLP does not converge has
    no claim (NaN): the run ends 'failed verification' (exit 1) with its
    report, result.json writing the claim as null, not a traceback."""
    from design.solvers.optimize.trust_region import Outcome, score

    def moved(population, caps, settings, rules, start, progress, anchor=True):
        d0 = population.space.scale(population.space.base_values)
        return Outcome(score(population, d0 + 0.1, settings), score(population, d0, settings),
                       caps)

    monkeypatch.setattr("design.run.solve.optimise", moved)
    monkeypatch.setattr("design.solvers.optimize.trust_region.optimiser_views",
                        lambda *args, **kwargs: ([None], "the fixed-design NLP failed: stalled"))
    code, result, last, stderr, report, out = solve(problem, capsys)
    assert code == 1
    assert result["status"] == FAILED
    assert result["message"].startswith("the optimiser could not evaluate its own design")
    assert result["objective"]["hold_time_s"] is None
    assert result["verification"]["hold_time_relative_difference"] is None
    assert not result["verification"]["passed"]
    assert "optimiser not evaluated" in last and "FAILED: failed verification" in stderr
    assert '<div class="banner failed" id="verdict">FAILED VERIFICATION: the optimiser' in report
