"""Exceptions the toolkit raises at its boundaries."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Problem:
    """One thing wrong with an input file.

    ``field`` is a dotted path such as ``finger.I.type`` or ``load.F[2]``.
    """

    file: str
    field: str
    message: str

    def __str__(self) -> str:
        where = f"{self.file}: {self.field}" if self.field else self.file
        return f"{where}: {self.message}"


class ProblemFileError(ValueError):
    """An input file (scene, problem or model) has one or more problems.

    All problems found in one validation pass are carried together so that a
    user can fix them in one go.
    """

    def __init__(self, problems: list[Problem]):
        self.problems = list(problems)
        super().__init__("\n".join(str(p) for p in self.problems))


class MethodUnsupportedError(ValueError):
    """A solver method was asked for a case it cannot solve correctly.

    Raised instead of returning a wrong number, e.g. the Frisch-Fay closed
    form for a finger whose EI varies along its length.
    """


class Interrupted(KeyboardInterrupt):
    """The user pressed Ctrl-C (SIGINT): the run stopped without a result.

    A ``KeyboardInterrupt``, so that no ``except Exception`` (a solver's
    fallback, a report's per-chapter guard) can take it for a failed solve.
    ``where`` says where the run stopped; ``written`` is true when it
    stopped only after its result files had been written completely.
    """

    def __init__(self, where: str, written: bool = False):
        self.where, self.written = where, written
        super().__init__(where)


class StudyError(ValueError):
    """A design study cannot run as asked: its case store holds cases from a
    different problem, or from an earlier run that ``resume`` was not asked
    to continue, or is not a case store; or its Dask scheduler cannot be
    reached. Raised before any case runs and before the store is changed."""


class StudyFailed(RuntimeError):
    """A case of a design study ended in an error (or was skipped after one):
    the run fails, naming each such case; the finished cases stay in the store."""
