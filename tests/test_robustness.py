"""The robustness table (design/solvers/optimize/robustness.py): each perturbed
scene changes the one thing it names, and the optimum beats the baseline
only where it holds longer, keeps the cap and does not jam."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from design.io.scene import load_scene
from design.run.grasp import setup_of
from design.solvers.optimize.robustness import (CASES, robustness_text, scenes, simulator,
                                              table)
from design.solvers.optimize.trust_region import LOOP_NEWTON_SOLVES

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def scene_setups():
    setup = setup_of(load_scene(ROOT / "problems" / "grasp_mean_bird_hard_spatial.yaml"))
    return setup, dict(zip([name for name, _ in CASES], scenes(setup)))


def test_each_scene_changes_what_it_names(scene_setups):
    """µ_f, drum phase (every finger 10° on, t = 0), bird, EI (every finger,
    every section), slots for finger 5; the nominal scene is the design's."""
    base, by_name = scene_setups
    assert by_name["nominal (finger µ 0.4, solid belt)"] == base
    assert by_name["finger µ 0"].finger_friction == 0.0
    assert by_name["finger µ 0.2"].finger_friction == 0.2
    turned = by_name["drum phase +10°"].grasper.fingers
    assert [f.mount.angle for f in turned] == pytest.approx(
        [f.mount.angle - np.radians(10.0) for f in base.grasper.fingers])
    assert by_name["2.05 kg bird"].bird.mass == pytest.approx(2.05)
    assert by_name["1.20 kg bird"].bird.mass == pytest.approx(1.20)
    soft = by_name["finger EI -20 %"].grasper.fingers
    for f, g in zip(soft, base.grasper.fingers):
        s = np.linspace(0.0, g.finger.length, 5)
        assert f.finger.stiffness.ei(s) == pytest.approx(0.8 * g.finger.stiffness.ei(s))
    assert by_name["finger 5 through a slotted pallet"].belt.slots == frozenset({"5"})
    assert base.belt.solid


#: what spatial_summary says of the model a run used
MODEL = {"finger_model": "spatial", "rtol": 1e-4, "atol_m": 1e-6, "max_step_s": 1e-2,
         "max_newton_solves_per_s": LOOP_NEWTON_SOLVES}


def run(hold: float, peak: float, jam: list | None = None, ok: bool = True) -> dict:
    return {"hold_time_s": hold, "max_finger_force_N": peak, "max_finger_force_finger": "5b",
            "jam": jam or [], "ok": ok, "message": "" if ok else "finger 5b's contact failed",
            "model": MODEL}


def test_the_optimum_beats_the_baseline_only_when_it_holds_longer_under_the_cap_unjammed():
    """Cap 20 N (1 % tolerance): longer and under it beats; shorter, over the
    cap by more than 1 %, jammed, or a run that ended early does not."""
    n = len(CASES)
    base = [run(0.35, 19.0)] * n
    opt = [run(0.40, 19.0), run(0.34, 18.0), run(0.40, 20.3), run(0.40, 18.0, ["finger 5b ..."]),
           run(0.40, 18.0, ok=False)] + [run(0.40, 20.1)] * (n - 5)
    t = table(base, opt, 20.0)
    assert t["model"] == MODEL
    beats = [r["optimum_beats_baseline"] for r in t["cases"]]
    assert beats[:5] == [True, False, False, False, False] and all(beats[5:])
    assert t["share_beaten"] == pytest.approx((n - 4) / n)
    assert t["broken_by"] == [name for name, _ in CASES[1:5]]
    assert [r["why_not"] for r in t["cases"][:5]] == [
        "", "holds no longer", "over the cap", "jams", "a run ended early"]
    assert t["cases"][4]["optimum_jam"].startswith("the run ended early")
    assert robustness_text(t).startswith(f"the optimum beats the baseline in {n - 4} of {n}")
    assert f"{CASES[2][0]} (over the cap)" in robustness_text(t)


def test_the_scenes_run_as_design_simulate_runs_them_within_the_loops_budget():
    """The perturbed scenes run on the scene's own integrator (rtol 1e-4,
    steps up to 10 ms: what a user re-running a scene gets), not the
    search's tighter one, and stop as failed runs past the design loop's
    contact-work budget, as the search's do."""
    problem = load_scene(ROOT / "problems" / "hold_time.yaml")
    own = problem.scene.settings.integrator
    used = simulator(own)
    assert (used.rtol, used.atol, used.max_step) == (own.rtol, own.atol, own.max_step) \
        == (1e-4, 1e-6, 1e-2)
    assert used.max_newton_solves == problem.settings.simulator.max_newton_solves \
        == LOOP_NEWTON_SOLVES
    assert problem.settings.simulator.rtol == 1e-6


def test_a_design_run_queues_the_scenes_on_that_simulator():
    """What the design run hands its background process: every case's scene
    for the design, on the scene's own simulator with the loop's budget."""
    from design.run.solve import design_space, submit_robustness

    class Queue:
        def submit_setups(self, label, setups, integrator):
            self.queued = label, setups, integrator

    problem = load_scene(ROOT / "problems" / "hold_time.yaml")
    space = design_space(problem)
    d0 = space.scale(space.base_values)
    queue = Queue()
    submit_robustness(problem, space, queue, "baseline", d0)
    label, setups, integrator = queue.queued
    assert label == "baseline" and setups == scenes(space.setup(d0))
    assert integrator == simulator(problem.scene.settings.integrator)


def test_each_run_records_the_model_it_ran_on(scene_setups):
    """A robustness run says which finger model and simulator it used (what
    result.json's robustness.model reports): those it was handed."""
    from dataclasses import replace

    from design.solvers.grasp.integrate import IntegratorSettings
    from design.solvers.optimize.model_check import spatial_summary

    base, _ = scene_setups
    used = simulator(IntegratorSettings(rtol=3e-4, atol=2e-6, max_step=4e-3))
    out = spatial_summary(replace(base, duration=0.02), used)
    assert out["ok"] and out["model"] == {"finger_model": "spatial", "rtol": 3e-4,
                                          "atol_m": 2e-6, "max_step_s": 4e-3,
                                          "max_newton_solves_per_s": LOOP_NEWTON_SOLVES}
