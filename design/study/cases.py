"""A study's cases and how to run them: :class:`Case`, :class:`StudyOptions`,
the cases' order (:func:`ordered`), their inputs' canonical JSON and the
row that tables a finished case (:func:`case_row`)."""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

from design.io.results import jsonable

#: statuses of cases that did not finish: their downstream cases are
#: skipped, and a resumed study runs them again
FAILED = ("error", "skipped")


@dataclass(frozen=True)
class Case:
    """One independent computation of a study.

    ``key`` names it, unique within the study and the same in every run
    (e.g. ``"start-03/cap-45.33N"``); ``inputs`` is everything that defines
    it, JSON-serialisable (stored with its result; a stored result is reused
    only for the same inputs); ``after`` is the key of the case whose result
    this one needs (a warm-start chain), a tuple of keys (it needs each of
    their results), or None.
    """

    key: str
    inputs: dict
    after: str | tuple[str, ...] | None = None

    @property
    def needs(self) -> tuple[str, ...]:
        """The keys of the cases this one needs, in order."""
        return () if self.after is None else \
            (self.after,) if isinstance(self.after, str) else tuple(self.after)

    @property
    def after_text(self) -> str | None:
        """``after`` as the case store keeps it: the key, or a JSON list of keys."""
        return self.after if self.after is None or isinstance(self.after, str) else \
            json.dumps(list(self.after))

    def upstream(self, done: dict[str, dict]) -> dict | None:
        """What the task gets from ``done`` (results by key): the needed
        case's result, ``{key: result}`` for several, None without any
        (or a result that is not in ``done``)."""
        if isinstance(self.after, str):
            return done.get(self.after)
        if self.after is None or any(k not in done for k in self.after):
            return None
        return {k: done[k] for k in self.after}

    def failed_upstream(self, done: dict[str, dict]) -> tuple[str, str] | None:
        """The first needed case that did not finish (missing: ``error``) and
        its status, or None."""
        for k in self.needs:
            status = done[k]["status"] if k in done else "error"
            if status in FAILED:
                return k, status
        return None


@dataclass(frozen=True)
class StudyOptions:
    """How a study runs.

    ``workers``: None, one worker process per core (a Dask LocalCluster); 1,
    in this process, one case after another, without Dask (the debugging
    path); N > 1, N local worker processes. ``scheduler``: the address of a
    running Dask scheduler (``tcp://HOST:PORT``), which overrides
    ``workers``; when neither is given, ``$DASK_SCHEDULER_ADDRESS`` if set.
    ``resume``: reuse the finished cases in ``store`` (``cases.sqlite``;
    None: no store, nothing to resume).
    """

    workers: int | None = None
    scheduler: str | None = None
    resume: bool = False
    store: Path | None = None

    def __post_init__(self):
        if self.workers is not None and (isinstance(self.workers, bool)
                                         or not isinstance(self.workers, int)
                                         or self.workers < 1):
            raise ValueError(f"workers: an integer >= 1 (1 runs the cases in this process), "
                             f"or None for one per core; not {self.workers!r}")
        if self.scheduler is not None and "://" not in self.scheduler:
            raise ValueError(f"scheduler: an address such as tcp://HOST:8786, "
                             f"not {self.scheduler!r}")
        if self.resume and self.store is None:
            raise ValueError("resume needs a case store (an output folder) to resume from")


def canonical(value: object) -> str:
    """``value`` as canonical JSON (sorted keys, no spaces, numpy values as
    plain numbers): equal inputs give equal text."""
    return json.dumps(jsonable(value), sort_keys=True, separators=(",", ":"), allow_nan=False)


def ordered(cases: list[Case]) -> list[Case]:
    """The cases with each after the case it needs, otherwise in the given
    order. ValueError, naming the key, for a repeated key, an ``after``
    that names no case, a cycle, or inputs that are not JSON."""
    by_key: dict[str, Case] = {}
    for case in cases:
        if case.key in by_key:
            raise ValueError(f"case {case.key!r} is given twice")
        try:
            canonical(case.inputs)
        except (TypeError, ValueError) as exc:
            raise ValueError(f"case {case.key!r}: inputs are not JSON: {exc}") from None
        by_key[case.key] = case
    for case in cases:
        for need in case.needs:
            if need not in by_key:
                raise ValueError(f"case {case.key!r}: after {need!r}, which is no case "
                                 f"of the study")
    out: list[Case] = []
    placed: set[str] = set()

    def place(case: Case, path: list[str]) -> None:
        """``case`` after every case it needs (depth first); ``path``: the
        cases waiting for it, to name a cycle."""
        if case.key in placed:
            return
        if case.key in path:
            raise ValueError(f"case {case.key!r}: its 'after' chain is a cycle: "
                             + " -> ".join(path[path.index(case.key):] + [case.key]))
        for need in case.needs:
            place(by_key[need], path + [case.key])
        out.append(case)
        placed.add(case.key)

    for case in cases:
        place(case, [])
    return out


def case_row(key: str, result: dict) -> dict:
    """A finished case as a table row: key, status, ``line_rate_per_min``,
    ``hold_time_s`` and ``max_finger_force_N`` when the result has them, the message of a case
    that failed, wall time (s) and worker."""
    row = {"key": key, "status": result["status"]}
    row.update({name: result[name] for name in ("line_rate_per_min", "hold_time_s",
                                                "max_finger_force_N")
                if result.get(name) is not None})
    if result["status"] in FAILED:
        row["message"] = result.get("message", "")
    row.update(wall_time_s=result.get("wall_time_s"), worker=result.get("worker"))
    return row
