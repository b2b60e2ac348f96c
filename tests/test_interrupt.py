"""Ctrl-C (SIGINT): any command stops within about a second, says where,
writes nothing (or every file) and exits 130; CasADi never turns the
interrupt into a failed solve that changes the answer."""

import os
import pickle
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import casadi as ca
import numpy as np
import pytest

from design.errors import Interrupted
from design.interrupt import handled, requested, stopped
from design.io.results import write_atomic
from tests.design_cases import shared_simulate_grasp, short_problem_file, short_setup

ROOT = Path(__file__).resolve().parents[1]
#: from Ctrl-C to the process's exit (s): the goal is 1 s; the rest is room
#: for a machine shared with other runs
PROMPT = 3.0


def ctrl_c_after(seconds: float) -> threading.Timer:
    timer = threading.Timer(seconds, os.kill, (os.getpid(), signal.SIGINT))
    timer.start()
    return timer


def test_ctrl_c_in_python_code_raises_at_once_and_the_old_handler_returns():
    before = signal.getsignal(signal.SIGINT)
    t0 = time.perf_counter()
    with pytest.raises(Interrupted) as caught, handled():
        ctrl_c_after(0.1)
        time.sleep(5)
    assert time.perf_counter() - t0 < 1.0
    assert "test_ctrl_c_in_python_code" in caught.value.where
    assert stopped(caught.value).endswith("nothing was written")
    assert signal.getsignal(signal.SIGINT) is before


def ctrl_c_inside_casadi() -> threading.Thread:
    """Ctrl-C once the main thread is inside a CasADi call (its innermost
    Python frame is CasADi's), so the interrupt does not land in the few
    microseconds of the caller's own code between calls."""
    main, casadi = threading.main_thread().ident, os.path.dirname(ca.__file__)

    def wait_and_kill():
        time.sleep(0.1)
        while not sys._current_frames()[main].f_code.co_filename.startswith(casadi):
            time.sleep(0.001)
        os.kill(os.getpid(), signal.SIGINT)

    thread = threading.Thread(target=wait_and_kill, daemon=True)
    thread.start()
    return thread


def slow_casadi_function() -> ca.Function:
    """A few ms per call: Newton on 20 000 cubic equations."""
    n = 20000
    x, z = ca.MX.sym("x", n), ca.MX.sym("z", n)
    root = ca.rootfinder("cubic", "newton", ca.Function("g", [z, x], [z ** 3 + z - x]))
    return ca.Function("slow", [x], [root(ca.DM.zeros(n), x)])


def test_ctrl_c_inside_a_casadi_call_is_not_taken_for_a_failed_solve():
    """CasADi turns a KeyboardInterrupt raised inside its call into a
    RuntimeError, which a solver's fallback would take for a failed solve:
    the interrupt must come out as itself when the call returns."""
    f, x = slow_casadi_function(), np.full(20000, 5.0)
    failed = 0
    with pytest.raises(Interrupted) as caught, handled():
        ctrl_c_inside_casadi()
        for _ in range(1000):
            try:
                f(x)
            except RuntimeError:
                failed += 1
    assert failed == 0
    assert "as a CasADi call returned" in caught.value.where


def test_under_a_profiler_the_run_stops_before_its_first_file(tmp_path):
    """With another profile hook in place the interrupt is only recorded
    inside CasADi; the run must still stop before it writes anything."""
    f, x = slow_casadi_function(), np.full(20000, 5.0)
    sys.setprofile(lambda frame, event, arg: None)
    try:
        with pytest.raises(Interrupted) as caught, handled():
            ctrl_c_after(0.1)
            while not requested():
                f(x)
            write_atomic(tmp_path / "result.json", "{}")
    finally:
        sys.setprofile(None)
    assert caught.value.where.startswith("before writing any result")
    assert not any(tmp_path.iterdir())


def test_ctrl_c_while_writing_lets_every_file_be_written(tmp_path):
    with pytest.raises(Interrupted) as caught, handled():
        write_atomic(tmp_path / "result.json", "{}")
        os.kill(os.getpid(), signal.SIGINT)
        time.sleep(0.2)
        write_atomic(tmp_path / "report.html", "<html></html>")
    assert caught.value.written
    assert sorted(p.name for p in tmp_path.iterdir()) == ["report.html", "result.json"]


#: the child's last stderr line: when its command returned (time.monotonic,
#: one clock for every process on the machine)
RETURNED = "command returned at monotonic time "


def run_and_interrupt(args: list[str], cue: str, tmp_path: Path, timeout: float = 60.0,
                      prelude: str = "") -> tuple[int, float, str, str]:
    """Run ``design args`` in a child process (its own session, as a
    terminal's Ctrl-C reaches a foreground job), send SIGINT to its group on
    the first progress line containing ``cue``; (exit status, seconds from
    the SIGINT to the exit, what they were spent on, stderr). The child's
    start-up is before the cue, so not in the time; of the time, the command
    itself takes milliseconds to stop and return, the interpreter's exit
    (module teardown) 0.2-0.5 s on the 2-core test machine."""
    code = (f"{prelude}\nimport sys, time\nfrom design.cli import main\nstatus = main({args!r})"
            f"\nprint(f'{RETURNED}{{time.monotonic()!r}}', file=sys.stderr)\nsys.exit(status)")
    child = subprocess.Popen([sys.executable, "-c", code], cwd=tmp_path, text=True,
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                             start_new_session=True)
    lines, deadline = [], time.monotonic() + timeout
    try:
        for line in child.stderr:
            lines.append(line)
            if cue in line:
                break
            assert time.monotonic() < deadline, "".join(lines)
        else:
            pytest.fail("the run ended before its cue:\n" + "".join(lines))
        sent = time.monotonic()
        os.killpg(child.pid, signal.SIGINT)
        rest = child.communicate(timeout=30)[1]
        took = time.monotonic() - sent
        returned = [float(line.removeprefix(RETURNED)) for line in rest.splitlines()
                    if line.startswith(RETURNED)]
        spent = (f"{took:.2f} s from Ctrl-C to exit, of which "
                 f"{returned[0] - sent if returned else float('nan'):.3f} s to return from "
                 f"the command, the rest the interpreter's exit")
        return child.returncode, took, spent, "".join(lines) + rest
    finally:
        if child.poll() is None:
            child.kill()
            child.wait()


def test_ctrl_c_stops_design_simulate_on_a_grasp_scene(tmp_path):
    out = tmp_path / "out"
    code, took, spent, stderr = run_and_interrupt(
        ["simulate", str(ROOT / "problems" / "grasp_mean_bird_hard.yaml"), "--out", str(out)],
        "grasp: t = 0.2", tmp_path)
    assert code == 130, stderr
    assert took < PROMPT, spent
    assert "interrupted (Ctrl-C): stopped" in stderr and "nothing was written" in stderr
    assert "Traceback" not in stderr
    assert not out.exists() or not any(out.iterdir())


#: the child's simulations: the baseline's, at the grasp scenes' default
#: tolerance, stands for every design's, so that the optimiser starts within
#: seconds (its NLP and Ipopt iterations are real); the run is the session's
#: (tests/design_cases.py, shared with test_run_status.py), handed over pickled
QUICK_SIMULATIONS = """
import pickle
from design.solvers.optimize import trust_region
with open({path!r}, "rb") as f:
    baseline = pickle.load(f)
trust_region.simulate_grasp = lambda setup, *args, **kwargs: baseline
"""


def test_ctrl_c_stops_design_solve_in_ipopt_and_claims_nothing(tmp_path):
    problem = short_problem_file(tmp_path / "problem.yaml",
                                 {"groups.upper.stiffness_scale": [0.5, 1.5]},
                                 max_iter=200, outer_iterations=3)
    baseline = tmp_path / "baseline.pickle"
    baseline.write_bytes(pickle.dumps(shared_simulate_grasp(short_setup())))
    out = tmp_path / "out"
    code, took, spent, stderr = run_and_interrupt(
        ["solve", str(problem), "--out", str(out)], "ipopt iteration 0:", tmp_path,
        prelude=QUICK_SIMULATIONS.format(path=str(baseline)))
    assert code == 130, stderr
    assert took < PROMPT, spent
    assert "interrupted (Ctrl-C): stopped" in stderr and "nothing was written" in stderr
    assert "Traceback" not in stderr
    assert "rejected" not in stderr and "accepted" not in stderr    # no outer iteration ended
    assert not (out / "result.json").exists()
