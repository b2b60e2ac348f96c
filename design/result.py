"""What :func:`design.simulate`, :func:`design.solve`, :func:`design.fit` and
:func:`design.check` return: a typed result.

Every result has a :class:`Status`, a ``message`` saying why, ``success``
(the status is a success: the command exits 0), the files it wrote
(``files``; none without an output folder), the summary a caller asks for
first (units in the field names: ``_s``, ``_N``, ``_m``), a ``verdict`` (the
command's closing line) and :meth:`Result.to_dict` / :meth:`Result.to_json`:
the run's whole record, which is what ``result.json`` holds (SI units; a
quantity's unit in its name or in the record's ``units``).

>>> r = BeamResult(status=Status.FINISHED, message="every case converged",
...                name="demo", cases=1, converged=1)
>>> r.success, r.to_dict()["status"]
(True, 'finished')
"""

from __future__ import annotations

import enum
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import ClassVar


class Status(enum.StrEnum):
    """How a run ended: ``result.json``'s ``status``. Each is its own string,
    so ``Status.VERIFIED == "verified"``."""

    #: a scene ran: every beam or contact case converged, a grasp reached its end
    FINISHED = "finished"
    #: a beam or contact case did not converge (each case says why)
    NOT_CONVERGED = "not converged"
    #: a grasp's integration stopped before its duration (the message says where)
    STOPPED = "stopped early"
    #: a design: the independent 4x finer simulation confirms the optimiser's design
    VERIFIED = "verified"
    #: a design: the loop accepted no design; the baseline, within the cap, is the answer
    NO_IMPROVEMENT = "no improvement found"
    #: a design: the simulation disagrees with the optimiser, or the design breaks the cap
    FAILED_VERIFICATION = "failed verification"
    #: a design: the optimiser could not work (every NLP failed, or it could not
    #: evaluate its own design)
    ERROR = "error"
    #: a fit: the model was fitted and its file reads back
    FITTED = "fitted"
    #: a fit: the solver failed, or the model file does not read back
    NOT_FITTED = "not fitted"
    #: a checked file has no problem
    VALID = "valid"
    #: a checked file has problems (``CheckResult.problems``)
    INVALID = "invalid"


#: the statuses that are a success
SUCCESS = frozenset({Status.FINISHED, Status.VERIFIED, Status.NO_IMPROVEMENT, Status.FITTED,
                     Status.VALID})


@dataclass(frozen=True, kw_only=True)
class Result:
    """A run's status and record; the subclasses add their summary."""

    #: the record's ``kind``
    KIND: ClassVar[str] = ""

    status: Status
    message: str
    #: the scene's or problem's name
    name: str = ""
    #: the files written, result.json first (none without an output folder)
    files: tuple[Path, ...] = ()
    #: the whole record as the run made it; read it through :meth:`to_dict`
    record: Mapping = field(default_factory=dict, repr=False, compare=False)

    @property
    def success(self) -> bool:
        """Whether the status is a success (the command's exit status 0)."""
        return self.status in SUCCESS

    @property
    def verdict(self) -> str:
        """One line: how the run ended and its main numbers."""
        return f"{self.status}: {self.message}"

    def to_dict(self) -> dict:
        """The record ``result.json`` holds: kind, name, status and message
        first, then the run's own fields."""
        out = {"kind": self.KIND, "name": self.name, "status": self.status.value,
               "message": self.message, **self.record}
        out.update(status=self.status.value, message=self.message)
        return out

    def to_json(self) -> str:
        """:meth:`to_dict` as the JSON text of ``result.json``."""
        from design.io.results import json_text

        return json_text(self.to_dict())


@dataclass(frozen=True, kw_only=True)
class BeamResult(Result):
    """A beam scene's loads solved (``kind: beam``); each case's tip, shape
    and error estimate are in ``to_dict()["cases"]``."""

    KIND: ClassVar[str] = "beam"
    method: str = ""
    #: loads solved, and how many of them converged
    cases: int = 0
    converged: int = 0
    #: the largest load-point error estimate (m)
    max_error_estimate_m: float = 0.0
    solve_time_s: float = 0.0


@dataclass(frozen=True, kw_only=True)
class ContactResult(Result):
    """A contact scene's poses solved (``kind: contact``)."""

    KIND: ClassVar[str] = "contact"
    method: str = ""
    cases: int = 0
    converged: int = 0
    #: each pose's contact force on the object (N; 0 without contact)
    forces_N: tuple[float, ...] = ()
    solve_time_s: float = 0.0


@dataclass(frozen=True, kw_only=True)
class GraspResult(Result):
    """A grasp simulated (``kind: grasp``): the hold, the peak finger force,
    the time series."""

    KIND: ClassVar[str] = "grasp"
    #: the longest window with the bird off the belt (N = 0) that it is put
    #: back from and carried on (s), and all such windows together (s)
    hold_time_s: float = 0.0
    total_hold_s: float = 0.0
    #: the largest force of any finger on the bird (N), which finger, when (s)
    max_finger_force_N: float = 0.0
    max_finger_force_finger: str = ""
    max_finger_force_time_s: float = 0.0
    #: held to the end, not carried on, or a finger past its fold force
    jammed: bool = False
    #: how far the bird's centre rose above its start (m)
    centre_rise_m: float = 0.0
    wall_time_s: float = 0.0

    @property
    def timeseries(self) -> dict:
        """The recorded instants as columns (numpy arrays), named with their
        units as in timeseries.csv: ``t_s``, ``X_m``, ``Z_m``, ``theta_rad``,
        ``N_N``, each finger's ``F<name>_N``, ..."""
        import numpy as np

        return {k: np.asarray(v, dtype=float if k != "mode" else object)
                for k, v in self.record.get("timeseries", {}).items()}

    @property
    def verdict(self) -> str:
        if self.status is not Status.FINISHED:
            return super().verdict
        from design.run.grasp import summary_line

        return summary_line(self.to_dict())


@dataclass(frozen=True, kw_only=True)
class DesignResult(Result):
    """A design problem optimised and verified (``kind: design``)."""

    KIND: ClassVar[str] = "design"
    #: the design's hold in the independent 4x finer simulation (s), the
    #: optimiser's own claim (s; None when it could not evaluate it) and the
    #: baseline's verified hold (s)
    hold_time_s: float = 0.0
    optimiser_hold_time_s: float | None = None
    baseline_hold_time_s: float = 0.0
    #: the design's largest finger force (N) and the bruise cap (N)
    max_finger_force_N: float = 0.0
    cap_N: float = 0.0
    #: each design variable's value at the answer, SI (m, rad, s, m/s, m/s^2;
    #: stiffness scales dimensionless); the baseline's with no improvement
    design: Mapping[str, float] = field(default_factory=dict)
    wall_time_s: float = 0.0
    #: a throughput problem's answer: birds per minute (None: a hold problem)
    line_rate_per_min: float | None = None

    @property
    def verdict(self) -> str:
        from design.run.solve import status_line

        return status_line(self.to_dict())


@dataclass(frozen=True, kw_only=True)
class FitResult(Result):
    """A finger's EI(s) or a belt's speed profile fitted (``kind: fit``)."""

    KIND: ClassVar[str] = "fit"
    #: ``finger`` or ``belt``
    target: str = ""
    warnings: tuple[str, ...] = ()

    @property
    def model_file(self) -> Path | None:
        """The model file written (finger.yaml or conveyor.yaml); None
        without an output folder."""
        name = self.record.get("model", {}).get("file")
        return next((path for path in self.files if path.name == name), None)

    @property
    def verdict(self) -> str:
        r = self.to_dict()
        model = f"; model: {self.model_file}" if self.model_file else ""
        if not self.success:
            return super().verdict
        if self.target == "finger":
            return (f"{self.name}: EI(s) by the {r['method']} model, {len(self.warnings)} "
                    f"warning(s){model}")
        f = r["fitted"]
        slows = (f" slowing to {f['final_speed']:.4g} m/s at {f['rate']:.3g} m/s^2 from "
                 f"t = {f['start_time']:.4g} s" if r["decelerates"] else " (constant)")
        return f"{self.name}: belt {f['speed']:.4g} m/s{slows}{model}"


@dataclass(frozen=True, kw_only=True)
class CheckResult(Result):
    """An input file validated (``design check``): what it describes, or
    every problem found."""

    #: the file's kind (``beam``, ``grasp``, ``design``, ``finger``, ...)
    kind: str = ""
    #: each problem: file, field, message (the allowed range)
    problems: tuple = ()
    #: what the file describes (e.g. a :class:`~design.io.grasp_scene.GraspScene`),
    #: None when it has problems
    value: object = field(default=None, repr=False, compare=False)

    def to_dict(self) -> dict:
        return {"kind": self.kind, "name": self.name, "status": self.status.value,
                "message": self.message, "problems": [str(p) for p in self.problems]}


#: the result class of each record kind
KINDS = {cls.KIND: cls for cls in (BeamResult, ContactResult, GraspResult, DesignResult,
                                   FitResult)}


def result_of(record: dict, ok: bool, files: tuple[Path, ...] = ()) -> Result:
    """The typed result of a run's ``record`` (a runner's result dict; ``ok``:
    the runner's verdict on it)."""
    cls = KINDS[record["kind"]]
    common = {"name": record.get("name") or "", "files": tuple(files), "record": record}
    return cls(**common, **_SUMMARIES[cls](record, ok))


def _cases(record: dict, ok: bool) -> dict:
    cases = record["cases"]
    done = sum(bool(c["converged"]) for c in cases)
    status = Status.FINISHED if ok else Status.NOT_CONVERGED
    message = "every case converged" if ok else \
        f"{len(cases) - done} of {len(cases)} cases did not converge (see each case's message)"
    return {"status": status, "message": message, "method": record["method"],
            "cases": len(cases), "converged": done, "solve_time_s": record["solve_time_s"]}


def _beam(record: dict, ok: bool) -> dict:
    return {**_cases(record, ok), "max_error_estimate_m": max(
        (c["error_estimate"] for c in record["cases"]), default=0.0)}


def _contact(record: dict, ok: bool) -> dict:
    return {**_cases(record, ok), "forces_N": tuple(c["force"] for c in record["cases"])}


def _grasp(record: dict, ok: bool) -> dict:
    s = record["summary"]
    return {"status": Status.FINISHED if ok else Status.STOPPED,
            "message": s["message"] or "the integration reached the scene's duration",
            **{k: s[k] for k in ("hold_time_s", "total_hold_s", "max_finger_force_N",
                                 "max_finger_force_finger", "max_finger_force_time_s",
                                 "jammed", "centre_rise_m")},
            "wall_time_s": record["stats"]["wall_time_s"]}


def _design(record: dict, ok: bool) -> dict:
    v = record["verification"]
    return {"status": Status(record["status"]), "message": record["message"],
            "hold_time_s": v["hold_time_s"],
            "optimiser_hold_time_s": record["objective"]["hold_time_s"],
            "baseline_hold_time_s": record["baseline"]["hold_time_s"],
            "max_finger_force_N": v["max_finger_force_N"], "cap_N": v["cap_N"],
            "design": dict(record["design"]), "wall_time_s": record["wall_time_s"],
            "line_rate_per_min": record.get("line_rate_per_min")}


def _fit(record: dict, ok: bool) -> dict:
    warnings = tuple(record["warnings"])
    message = (f"fitted with {len(warnings)} warning(s)" if ok else
               "the fit did not succeed" + (f": {'; '.join(warnings)}" if warnings else ""))
    return {"status": Status.FITTED if ok else Status.NOT_FITTED, "message": message,
            "target": record["target"], "warnings": warnings}


_SUMMARIES = {BeamResult: _beam, ContactResult: _contact, GraspResult: _grasp,
              DesignResult: _design, FitResult: _fit}
