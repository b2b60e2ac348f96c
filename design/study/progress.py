"""A study's progress on stderr: one live line while it runs,

    <label>: cases done/total, best verified hold so far, elapsed, about T left

(or the best verified line rate, for a line-speed study: ``goal``)
(on a terminal; otherwise one plain line per finished case), and a table of
the cases at the end. The time left is the elapsed time per case run so
far (cases from the store excluded) times the cases left, so it counts
the workers' parallelism.
"""

from __future__ import annotations

import sys
import time
from typing import TextIO

from rich.console import Console
from rich.live import Live
from rich.table import Table
from rich.text import Text

from design.study.cases import FAILED, case_row

#: (row field, column header, format) of the case tables, in order; a column
#: is shown when some row has its field
COLUMNS = (("key", "key", "{}"), ("status", "status", "{}"),
           ("line_rate_per_min", "rate (birds/min)", "{:.1f}"), ("hold_time_s", "hold (s)", "{:.4f}"),
           ("max_finger_force_N", "peak (N)", "{:.2f}"), ("wall_time_s", "wall time (s)", "{:.1f}"),
           ("worker", "worker", "{}"), ("finished_at", "finished (UTC)", "{}"),
           ("message", "message", "{}"))

#: what a study's progress line calls best: (result field, words, format)
HOLD = ("hold_time_s", "best verified hold", "{:.4f} s")
RATE = ("line_rate_per_min", "best verified rate", "{:.1f} birds/min")

#: the width of a table written to a file or pipe (a terminal's is its own)
PIPED_WIDTH = 200


class StudyProgress:
    """Shows a running study (see the module docstring); ``quiet`` shows
    nothing. ``live``: None, a live line when ``stream`` is a terminal;
    ``goal``: what the line calls best (:data:`HOLD`, :data:`RATE`)."""

    def __init__(self, quiet: bool = False, stream: TextIO | None = None,
                 live: bool | None = None, goal: tuple = HOLD):
        self.quiet, self.goal = quiet, goal
        self.console = console(stream or sys.stderr)
        self.live = self.console.is_terminal if live is None else live
        self._display: Live | None = None
        self.label, self.total, self.done, self.ran = "", 0, 0, 0
        self.best: float | None = None
        self.t0 = time.monotonic()

    def start(self, label: str, total: int, stored: dict[str, dict], where: str) -> None:
        """The study starts: ``total`` cases, ``stored`` of them (key ->
        result) from the store, the rest to run ``where``."""
        self.label, self.total, self.done, self.ran = label, total, len(stored), 0
        for result in stored.values():
            self._note(result)
        self.t0 = time.monotonic()
        if self.quiet:
            return
        reused = f", {len(stored)} from the store" if stored else ""
        self.console.print(f"{label}: {total} cases{reused}; running on {where}")
        if self.live:
            self._display = Live(console=self.console, get_renderable=self.line,
                                 refresh_per_second=2, transient=True)
            self._display.start()

    def finished(self, key: str, result: dict) -> None:
        """A case finished (it is in the store)."""
        self.done, self.ran = self.done + 1, self.ran + 1
        self._note(result)
        if not self.quiet and not self.live:
            rate = f", {result['line_rate_per_min']:.1f} birds/min" \
                if result.get("line_rate_per_min") is not None else ""
            hold = f", hold {result['hold_time_s']:.4f} s" \
                if result.get("hold_time_s") is not None else ""
            self.console.print(f"{key}: {result['status']}{rate}{hold}; {self.line()}")

    def traceback(self, key: str, text: str) -> None:
        """A case's task raised: its traceback (shown even when quiet)."""
        self.console.print(Text(f"case {key!r} failed:\n{text.rstrip()}"))

    def stop(self) -> None:
        """The study ended or was stopped: the live line goes."""
        if self._display is not None:
            self._display.stop()
            self._display = None

    def summary(self, results: dict[str, dict]) -> None:
        """The table of every case (key, status, hold, wall time, worker)."""
        if not self.quiet:
            self.console.print(case_table([case_row(k, r) for k, r in results.items()],
                                          title=self.line()))

    def line(self) -> Text:
        """The progress line now."""
        elapsed = time.monotonic() - self.t0
        _, words, form = self.goal
        best = form.format(self.best) if self.best is not None else "none yet"
        left = f"about {_duration(elapsed / self.ran * (self.total - self.done))} left" \
            if self.ran and self.done < self.total else \
            ("done" if self.done >= self.total else "time left not known yet")
        return Text(f"{self.label}: cases {self.done}/{self.total}, {words} "
                    f"{best}, elapsed {_duration(elapsed)}, {left}")

    def _note(self, result: dict) -> None:
        value = result.get(self.goal[0])
        if value is not None and result.get("verified", True) and \
                result["status"] not in FAILED and (self.best is None or value > self.best):
            self.best = value


def console(stream: TextIO) -> Console:
    """A rich console on ``stream`` that prints text as it is (no markup);
    one that is not a terminal is not wrapped at 80 columns."""
    return Console(file=stream, highlight=False, markup=False, soft_wrap=True,
                   width=None if stream.isatty() else PIPED_WIDTH)


def case_table(rows: list[dict], title: str | None = None) -> Table:
    """The rows (:func:`~design.study.cases.case_row`) as a table with the
    :data:`COLUMNS` that some row has."""
    shown = [(field, header, form) for field, header, form in COLUMNS
             if any(row.get(field) is not None for row in rows)]
    table = Table(title=title, title_justify="left")
    for field, header, form in shown:
        table.add_column(header, justify="right" if form != "{}" else "left")
    for row in rows:
        table.add_row(*(form.format(row[field]) if row.get(field) is not None else "-"
                        for field, header, form in shown))
    return table


def _duration(seconds: float) -> str:
    """``42 s``, ``3 min 05 s``, ``2 h 07 min``."""
    s = int(round(seconds))
    if s < 60:
        return f"{s} s"
    if s < 3600:
        return f"{s // 60} min {s % 60:02d} s"
    return f"{s // 3600} h {s % 3600 // 60:02d} min"
