"""Running a validated scene: each kind's runner returns a :class:`RunOutput`,
which the API (design/api.py) turns into a typed result (design/result.py)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

#: progress(message) callback for long runs
Progress = Callable[[str], None]


@dataclass
class RunOutput:
    """What a run produced: its record and CSV tables.

    ``result`` is the runner's record; the typed result's ``to_dict()``
    (design/result.py) adds its status and message, and result.json holds that."""

    result: dict
    tables: dict[str, list[dict]] = field(default_factory=dict)
    #: true when every case converged / the run succeeded
    ok: bool = True
    #: further text files by name (e.g. the optimum as a scene file)
    files: dict[str, str] = field(default_factory=dict)
    #: the objects behind the result that its report draws (runs, setups)
    artifacts: dict = field(default_factory=dict)
