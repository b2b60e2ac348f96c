"""The design on the other finger model: does the gain survive the spatial rod?

The optimiser's NLP and its verification both model the fingers as the
thesis does, bending in their own planes only (``planar``). On the design
scenes the bird's surface normal at the contacts lies up to 0.7 out of
those planes, outside that model's validity (design/solve/grasp/validity.py),
and the validation against chapter V runs the fingers as rods bending both
ways (``spatial``). So every design run simulates its baseline and its
optimum once more, the same scene with the spatial finger, and says whether
the optimum still holds at least as long as the baseline and keeps the
cap: the cap given as a rule (``baseline``, a fraction of it, or newtons)
is resolved on the spatial baseline's own peak.

The spatial runs (6-8 s CPU each on the main problem) go to one background
process, the baseline's at the start of the run while the optimiser works,
the optimum's as soon as the design loop has picked it, so that they cost
the run little wall time on a machine with a free core. A check that fails
(the simulation raises or ends early) fails the run: no silent gaps.
"""

from __future__ import annotations

import multiprocessing
import time
from concurrent.futures import Future, ProcessPoolExecutor
from dataclasses import replace

import numpy as np

from design.solve.grasp.integrate import IntegratorSettings
from design.solve.grasp.simulation import SPATIAL_NODES, GraspSetup, simulate_grasp
from design.solve.grasp.validity import validity_problems
from design.solve.optimize.trust_region import CAP_TOLERANCE

#: the model the check runs and the one it checks
CHECK_MODEL, DESIGN_MODEL = "spatial", "planar"


def spatial_summary(setup: GraspSetup, integrator: IntegratorSettings) -> dict:
    """The setup simulated with the spatial finger: hold, peak and the
    run's own validity problems (SI), and its CPU time."""
    t0 = time.process_time()
    run = simulate_grasp(replace(setup, finger_model=CHECK_MODEL), integrator, SPATIAL_NODES)
    s = run.summary
    return {"hold_time_s": s["hold_time_s"], "hold_windows": s["hold_windows"],
            "max_finger_force_N": s["max_finger_force_N"],
            "max_finger_force_finger": s["max_finger_force_finger"],
            "max_finger_force_time_s": float(s["max_finger_force_time_s"]),
            "ok": s["ok"], "message": s["message"],
            "model_warnings": validity_problems(s["validity"]),
            "cpu_time_s": time.process_time() - t0}


class ModelCheck:
    """Spatial runs of designs of a population, in a background process.

    ``submit(label, population, d)`` starts every bird's run of the scaled
    design d; ``result(...)`` waits for a baseline's and an optimum's runs
    and compares them. ``close()`` (or the ``with`` block) stops the
    process, also on Ctrl-C."""

    def __init__(self, integrator: IntegratorSettings):
        self.integrator = integrator
        self._pool = ProcessPoolExecutor(1, mp_context=multiprocessing.get_context("spawn"))
        self._runs: dict[str, list[Future]] = {}

    def __enter__(self) -> ModelCheck:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def close(self) -> None:
        """Stop the background process, also amid a run (Ctrl-C, a failed
        case): a simulation still running there is not waited for."""
        # Python 3.14's ProcessPoolExecutor.terminate_workers; before it, the
        # same by hand (shutdown forgets the processes, so they are taken first)
        processes = list((getattr(self._pool, "_processes", None) or {}).values())
        self._pool.shutdown(wait=False, cancel_futures=True)
        for process in processes:
            process.terminate()

    def submit(self, label: str, population, d: np.ndarray) -> None:
        """Start the spatial runs of design d (scaled) for every bird, once per label."""
        if label not in self._runs:
            self._runs[label] = [self._pool.submit(spatial_summary, m.space.setup(d),
                                                   self.integrator)
                                 for m in population.members]

    def summaries(self, label: str) -> list[dict]:
        """Every bird's spatial run of the design submitted as ``label``; a
        run that ended early fails the check (RuntimeError naming it)."""
        runs = [f.result() for f in self._runs[label]]
        for run in runs:
            if not run["ok"]:
                raise RuntimeError(f"the spatial check of the {label} design ended early: "
                                   f"{run['message']}")
        return runs

    def result(self, population, cap_spec, baseline: str = "baseline",
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
