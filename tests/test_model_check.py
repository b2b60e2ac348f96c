"""The design on the spatial finger model (design/solvers/optimize/model_check.py):
its runs in the background process are the spatial simulation itself, its
verdict follows the cap's rule on the spatial baseline, a second process
shares its runs while the run waits, and closing it stops a run in
progress."""

import json
import subprocess
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from design.io.design_problem import Cap
from design.io.scene import load_scene
from design.run.solve import design_space
from design.solvers.grasp.simulation import simulate_grasp
from design.solvers.optimize.model_check import ModelCheck, check_text, compare, spatial_summary
from design.solvers.optimize.population import Member, Population
from design.solvers.optimize.trust_region import LOOP_SIMULATOR
from design.solvers.optimize.variables import DesignSpace

ROOT = Path(__file__).resolve().parents[1]


def placed_bird(duration: float) -> DesignSpace:
    """The main problem's space (the mean bird placed on finger 4a), cut to
    ``duration`` s: 0.08 s is 1.6 s CPU of spatial rod and finger 4a presses
    about 30 N in it."""
    space = design_space(load_scene(ROOT / "problems" / "hold_time_planar.yaml"))
    return DesignSpace(replace(space.baseline, duration=duration), space.variables)


def test_the_background_run_is_the_spatial_simulation_and_runs_no_script_twice(tmp_path):
    """A user's script with no ``if __name__ == "__main__"`` guard starts
    the check: the background run gives the same numbers as the spatial
    simulation in this process, and not the planar model's (finger 4a's peak
    differs by 0.27 N between the two), and the script runs once (a
    multiprocessing child would import it again and run it twice)."""
    script, marks = tmp_path / "user.py", tmp_path / "marks"
    script.write_text(
        "import json, sys\n"
        f"open({str(marks)!r}, 'a').write('x')\n"
        f"sys.path.insert(0, {str(ROOT)!r})\n"
        "from tests.test_model_check import placed_bird\n"
        "from design.solvers.optimize.model_check import ModelCheck\n"
        "from design.solvers.optimize.population import Population\n"
        "from design.solvers.optimize.trust_region import LOOP_SIMULATOR\n"
        "space = placed_bird(0.08)\n"
        "with ModelCheck(LOOP_SIMULATOR) as check:\n"
        "    check.submit('baseline', Population.of(space), space.scale(space.base_values))\n"
        "    print(json.dumps(check.summaries('baseline')[0]))\n")
    done = subprocess.run([sys.executable, str(script)], capture_output=True, text=True,
                          timeout=120)
    assert done.returncode == 0, done.stderr
    assert marks.read_text() == "x"
    background = json.loads(done.stdout)
    space = placed_bird(0.08)
    d0 = space.scale(space.base_values)
    here = spatial_summary(space.setup(d0), LOOP_SIMULATOR)
    for key in ("hold_time_s", "max_finger_force_N", "max_finger_force_time_s"):
        assert background[key] == here[key]
    planar = simulate_grasp(space.setup(d0), LOOP_SIMULATOR).summary
    assert abs(planar["max_finger_force_N"] - here["max_finger_force_N"]) > 0.1


def test_closing_stops_a_run_in_progress():
    """Ctrl-C or a failed case closes the check: the background run (9 s of
    spatial rod here) is stopped, not waited for."""
    space = placed_bird(1.0)
    check = ModelCheck(LOOP_SIMULATOR)
    check.submit("baseline", Population.of(space), space.scale(space.base_values))
    time.sleep(1.0)                          # the process is importing or running
    process = check._process
    t0 = time.perf_counter()
    check.close()
    assert process.poll() is not None and time.perf_counter() - t0 < 5.0


def test_the_waiting_process_makes_the_runs_the_background_has_not_begun():
    """Three short spatial runs queued, then waited for at once: this
    process makes some of them itself (the background one is still
    starting), each run is claimed by one process only (none left
    unclaimed, none repeated), and each gives what this process computes."""
    space = placed_bird(0.02)
    setups = [space.setup(d) for d in (space.scale(space.base_values), np.full(8, 0.3),
                                       np.full(8, 0.6))]
    with ModelCheck(LOOP_SIMULATOR) as check:
        check.submit_setups("three", setups)
        runs = check.runs("three")
        folder = Path(check._folder.name)
        assert check.ran_here >= 1
        assert sorted(p.name for p in folder.glob("*.claimed")) == \
            ["1.claimed", "2.claimed", "3.claimed"] and not list(folder.glob("*.task"))
    for setup, run in zip(setups, runs):
        here = spatial_summary(setup, LOOP_SIMULATOR)
        assert run["hold_time_s"] == here["hold_time_s"]
        assert run["max_finger_force_N"] == here["max_finger_force_N"]


def run(hold: float, peak: float, warnings=()) -> dict:
    return {"hold_time_s": hold, "max_finger_force_N": peak, "max_finger_force_finger": "4a",
            "model_warnings": list(warnings), "cpu_time_s": 1.0, "ok": True}


TWO = Population((Member("small", None), Member("large", None)), "worst")


@pytest.mark.parametrize("cap, optimum, survives, why", [
    # the baseline's peak as the rule: each bird's cap is its spatial baseline peak
    (Cap(relative=1.0), [run(0.30, 19.0), run(0.25, 29.0)], True, ""),
    # the population's hold is the worst bird's: 0.19 s < 0.20 s
    (Cap(relative=1.0), [run(0.19, 19.0), run(0.40, 29.0)], False, "shorter hold"),
    # 0.9 x 30 N = 27 N for the large bird, which presses 29 N
    (Cap(relative=0.9), [run(0.30, 15.0), run(0.30, 29.0)], False, "over the cap"),
    # newtons stay newtons; within the verification's 1 % tolerance
    (Cap(value=25.0), [run(0.30, 25.2), run(0.30, 24.0)], True, ""),
])
def test_the_verdict_applies_the_caps_rule_to_the_spatial_baseline(cap, optimum, survives,
                                                                     why):
    base = [run(0.20, 20.0), run(0.22, 30.0, ["finger 5a passed 9 mm through the belt"])]
    check = compare(TWO, cap, base, optimum, LOOP_SIMULATOR)
    assert check["gain_survives"] is survives
    assert check["caps_N"] == pytest.approx([cap.resolve(20.0), cap.resolve(30.0)])
    assert check["hold_time_s"]["baseline"] == 0.20
    assert check["model_warnings"] == ["baseline (large): finger 5a passed 9 mm through the belt"]
    text = check_text(check)
    assert ("the gain survives" in text) is survives and why in text

