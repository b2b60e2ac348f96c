"""The design on the other finger model: does the gain survive the spatial rod?

The optimiser's NLP and its verification both model the fingers as the
thesis does, bending in their own planes only (``planar``). On the design
scenes the bird's surface normal at the contacts lies up to 0.7 out of
those planes, outside that model's validity (design/solvers/grasp/validity.py),
and the validation against chapter V runs the fingers as rods bending both
ways (``spatial``). So every design run simulates its baseline and its
optimum once more, the same scene with the spatial finger, and says whether
the optimum still holds at least as long as the baseline and keeps the
cap: the cap given as a rule (``baseline``, a fraction of it, or newtons)
is resolved on the spatial baseline's own peak.

The spatial runs (seconds each on the main problem) go to one background
process, the baseline's at the start of the run while the optimiser works,
the optimum's as soon as the design loop has picked it, so that they cost
the run little wall time on a machine with a free core. It runs at a lower
priority: the design loop's simulations come first (and do not count it as
load when they look for a free core, design/solvers/optimize/ahead.py). Once the run waits
for them, its own core is free too, and it makes the runs the background
process has not begun itself (a second process would spend that wait
importing and building). The background process is
a fresh interpreter running this module (``python -m``), not a
multiprocessing child: those import the caller's main script again, which
would run a user's unguarded ``design.api.solve(...)`` script twice. Tasks
and results pass as pickles through a private temporary folder; a process
claims a task by renaming its file, so each runs once. A check that fails
(the simulation raises or ends early, a process dies) fails the run: no
silent gaps.
"""

from __future__ import annotations

import os
import pickle
import subprocess
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from design.solvers.grasp.integrate import IntegratorSettings
from design.solvers.grasp.simulation import SPATIAL_NODES, GraspSetup, simulate_grasp
from design.solvers.grasp.validity import validity_problems
from design.solvers.optimize.ahead import YIELDING
from design.solvers.optimize.trust_region import CAP_TOLERANCE

#: the model the check runs and the one it checks
CHECK_MODEL, DESIGN_MODEL = "spatial", "planar"
#: the label of the baseline design's runs
BASELINE = "baseline"
#: how much lower the background processes' priority is (Unix niceness)
NICENESS = 10


def spatial_summary(setup: GraspSetup, integrator: IntegratorSettings) -> dict:
    """The setup simulated with the spatial finger: hold, peak and the
    run's own validity problems (SI), the model it ran on, and its CPU time."""
    t0 = time.process_time()
    run = simulate_grasp(replace(setup, finger_model=CHECK_MODEL), integrator, SPATIAL_NODES)
    s = run.summary
    return {"hold_time_s": s["hold_time_s"], "hold_windows": s["hold_windows"],
            "max_finger_force_N": s["max_finger_force_N"],
            "max_finger_force_finger": s["max_finger_force_finger"],
            "max_finger_force_time_s": float(s["max_finger_force_time_s"]),
            "ok": s["ok"], "message": s["message"], "jam": s["jam"],
            "model_warnings": validity_problems(s["validity"]),
            "model": {"finger_model": CHECK_MODEL, "rtol": integrator.rtol,
                      "atol_m": integrator.atol, "max_step_s": integrator.max_step,
                      "max_newton_solves_per_s": integrator.max_newton_solves},
            "cpu_time_s": time.process_time() - t0}


class ModelCheck:
    """Spatial runs of designs of a population, in a background process.

    ``submit(label, population, d)`` queues every bird's run of the scaled
    design d, ``submit_setups(label, setups)`` any scenes' (the robustness
    table's, design/solvers/optimize/robustness.py); ``result(...)`` waits
    for a baseline's and an optimum's runs and compares them, making the
    runs the background process has not begun itself while it waits
    (:attr:`ran_here`). ``close()`` (or the ``with`` block) stops the
    processes, also amid a run (Ctrl-C, a failed case): a simulation still
    running there is not waited for."""

    #: how often a wait looks for a result (s)
    POLL = 0.02

    def __init__(self, integrator: IntegratorSettings):
        self.integrator = integrator
        self._folder = tempfile.TemporaryDirectory(prefix="design-model-check-")
        #: the background interpreter (started with the first task)
        self._process: subprocess.Popen | None = None
        self._tasks: list[Path] = []
        self._runs: dict[str, list[Path]] = {}
        #: runs this process made itself while it waited
        self.ran_here = 0

    def __enter__(self) -> ModelCheck:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def close(self) -> None:
        process = self._process
        if process is not None:
            if process.poll() is None:
                process.kill()
                process.wait()
            process.stdin.close()
            YIELDING.discard(process.pid)
        self._folder.cleanup()

    @property
    def _log(self) -> Path:
        return Path(self._folder.name) / "worker.log"

    def _start(self) -> None:
        """The background interpreter; it finds this package where this
        process found it."""
        root = str(Path(__file__).resolve().parents[3])
        env = dict(os.environ)
        env["PYTHONPATH"] = os.pathsep.join(p for p in (root, env.get("PYTHONPATH")) if p)
        with open(self._log, "wb") as log:
            self._process = subprocess.Popen(
                [sys.executable, "-m", __spec__.name], stdin=subprocess.PIPE,
                stdout=subprocess.DEVNULL, stderr=log, env=env)
        YIELDING.add(self._process.pid)

    def _send(self, tasks: list[Path]) -> None:
        self._process.stdin.write("".join(f"{task}\n" for task in tasks).encode())
        self._process.stdin.flush()

    def submit(self, label: str, population, d: np.ndarray) -> None:
        """Queue the spatial runs of design d (scaled) for every bird, once per label."""
        self.submit_setups(label, [m.space.setup(d) for m in population.members])

    def submit_setups(self, label: str, setups: list[GraspSetup],
                      integrator: IntegratorSettings | None = None) -> None:
        """Queue the spatial runs of ``setups``, once per label, on
        ``integrator`` (None: the check's)."""
        if label in self._runs:
            return
        tasks = []
        for setup in setups:
            task = Path(self._folder.name) / f"{len(self._tasks) + len(tasks) + 1}.task"
            task.write_bytes(pickle.dumps((setup, integrator or self.integrator)))
            tasks.append(task)
        self._tasks += tasks
        if self._process is None:
            self._start()
        self._send(tasks)
        self._runs[label] = [task.with_suffix(".result") for task in tasks]

    def _wait(self, path: Path) -> dict:
        while not path.exists():
            # this process only waits: its core makes a run no process has begun
            if any(_claim_and_run(task) for task in self._tasks):
                self.ran_here += 1
                continue
            if self._process.poll() is not None:
                log = self._log.read_text(errors="replace")
                raise RuntimeError(f"the spatial check's process ended (exit status "
                                   f"{self._process.returncode}) before its run "
                                   f"{path.stem}: {log.strip()[-2000:]}")
            time.sleep(self.POLL)
        run = pickle.loads(path.read_bytes())
        if "error" in run:
            raise RuntimeError(f"the spatial check's run {path.stem} failed: {run['error']}")
        return run

    def runs(self, label: str) -> list[dict]:
        """The spatial runs submitted as ``label`` (:func:`spatial_summary`),
        ended early or not; a run that raised fails (RuntimeError naming it)."""
        return [self._wait(path) for path in self._runs[label]]

    def summaries(self, label: str) -> list[dict]:
        """Every bird's spatial run of the design submitted as ``label``; a
        run that failed or ended early fails the check (RuntimeError naming
        it)."""
        runs = self.runs(label)
        for run in runs:
            if not run["ok"]:
                raise RuntimeError(f"the spatial check of the {label} design ended early: "
                                   f"{run['message']}")
        return runs

    def result(self, population, cap_spec, baseline: str = BASELINE,
               optimum: str = "optimum") -> dict:
        """:func:`compare` of the runs submitted as ``baseline`` and ``optimum``."""
        return compare(population, cap_spec, self.summaries(baseline), self.summaries(optimum),
                       self.integrator)


def compare(population, cap_spec, base: list[dict], best: list[dict],
            integrator: IntegratorSettings) -> dict:
    """result.json's ``model_check`` from every bird's spatial runs
    (:func:`spatial_summary`) of the baseline and the optimum: their holds
    and peaks, each bird's cap resolved on its spatial baseline's peak, and
    whether the optimum's gain survives (the population's hold at least the
    baseline's, and every bird under its cap, with the verification's
    tolerance)."""
    caps = np.array([cap_spec.resolve(b["max_finger_force_N"]) for b in base])
    holds = {label: population.hold([r["hold_time_s"] for r in runs])
             for label, runs in (("baseline", base), ("optimum", best))}
    within = bool(all(o["max_finger_force_N"] <= c * (1 + CAP_TOLERANCE)
                  for o, c in zip(best, caps)))
    longer = holds["optimum"] >= holds["baseline"]
    warnings = []
    for m, b, o in zip(population.members, base, best):
        who = f" ({m.name})" if len(base) > 1 else ""
        warnings += [f"{label}{who}: {w}" for label, r in (("baseline", b), ("optimum", o))
                     for w in r["model_warnings"]]
    return {
        "finger_model": CHECK_MODEL, "design_model": DESIGN_MODEL,
        "contact_nodes": SPATIAL_NODES,
        "integrator": {"rtol": integrator.rtol, "atol": integrator.atol},
        "hold_time_s": holds,
        "caps_N": caps.tolist(),
        "birds": [{"bird": m.name, "cap_N": float(c), "baseline": b, "optimum": o}
                  for m, c, b, o in zip(population.members, caps, base, best)],
        "holds_at_least_as_long": bool(longer), "within_cap": within,
        "gain_survives": bool(longer and within),
        "model_warnings": warnings,
    }


def check_text(check: dict) -> str:
    """One sentence on the spatial check for the command's closing line."""
    h = check["hold_time_s"]
    peak = max(b["optimum"]["max_finger_force_N"] for b in check["birds"])
    cap = max(check["caps_N"])
    verdict = ("the gain survives" if check["gain_survives"] else
               "the gain does NOT survive: " + ", ".join(
                   w for w, bad in (("shorter hold", not check["holds_at_least_as_long"]),
                                    ("over the cap", not check["within_cap"])) if bad))
    n = len(check["model_warnings"])
    own = f" ({n} validity problem(s) of that model's own: result.json model_check)" if n else ""
    return (f"on the spatial finger model: hold {h['baseline']:.4f} -> {h['optimum']:.4f} s, "
            f"peak {peak:.2f} N (cap {cap:.2f} N on its own baseline): {verdict}{own}")


def _serve() -> None:
    """The background process: each line of standard input names a task
    file, whose run it makes (:func:`_claim_and_run`). It runs at a lower
    priority (:data:`NICENESS`): the design loop's simulations come first,
    it takes the cores they leave free."""
    if hasattr(os, "nice"):
        os.nice(NICENESS)
    for line in sys.stdin:
        _claim_and_run(Path(line.strip()))


def _claim_and_run(task: Path) -> bool:
    """Make the run of the task file ``task`` (a pickled setup and
    integrator) unless a process has claimed it: claimed by renaming it
    (another process that claimed it first leaves nothing to rename), its
    :func:`spatial_summary`, or the error, written beside it as ``.result``
    (renamed into place whole, so that a reader never sees half of it).
    Whether it made it."""
    claimed = task.with_suffix(".claimed")
    try:
        task.rename(claimed)
    except FileNotFoundError:
        return False
    try:
        run = spatial_summary(*pickle.loads(claimed.read_bytes()))
    except Exception as exc:                     # noqa: BLE001  reported by the waiting run
        run = {"error": f"{type(exc).__name__}: {exc}"}
    partial = task.with_suffix(".partial")
    partial.write_bytes(pickle.dumps(run))
    partial.replace(task.with_suffix(".result"))
    return True


if __name__ == "__main__":
    _serve()
