"""What the commands share: progress lines, input problems, the output
folder, argument types, and a result's closing lines and exit status."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from design.errors import ProblemFileError
from design.result import Result, Status

EXIT_OK, EXIT_FAILED, EXIT_BAD_INPUT = 0, 1, 2
#: 128 + SIGINT: what a shell reports for a command stopped by Ctrl-C
EXIT_INTERRUPTED = 130
#: the command's exit status for each way a run ends
EXIT_STATUS = {
    Status.FINISHED: EXIT_OK, Status.VERIFIED: EXIT_OK, Status.NO_IMPROVEMENT: EXIT_OK,
    Status.FITTED: EXIT_OK, Status.VALID: EXIT_OK,
    Status.NOT_CONVERGED: EXIT_FAILED, Status.STOPPED: EXIT_FAILED,
    Status.FAILED_VERIFICATION: EXIT_FAILED, Status.ERROR: EXIT_FAILED,
    Status.NOT_FITTED: EXIT_FAILED,
    Status.INVALID: EXIT_BAD_INPUT,
}


def progress(message: str) -> None:
    """A long run's progress line, on stderr."""
    print(f"[design] {message}", file=sys.stderr, flush=True)


def report_problems(exc: ProblemFileError) -> int:
    """Print every problem of an input file; the bad-input exit status."""
    for problem in exc.problems:
        print(f"error: {problem}", file=sys.stderr)
    n = len(exc.problems)
    print(f"{n} problem{'s' if n != 1 else ''} found; nothing was written.", file=sys.stderr)
    return EXIT_BAD_INPUT


def closing(result: Result) -> int:
    """Print the files a run wrote, its verdict and, if it did not succeed,
    why (on stderr); its exit status."""
    for path in result.files:
        print(path)
    print(result.verdict)
    if not result.success:
        print(f"FAILED: {result.status}: {result.message}", file=sys.stderr)
    return EXIT_STATUS[result.status]


def output_folder(given: str | None, default: Path) -> Path | None:
    """The run's output folder (``--out``, else ``default``), checked before
    the run starts; None, with the reason printed, when it cannot be written."""
    from design.io.results import OutputFolderError, check_output_folder

    out = Path(given) if given else default
    try:
        check_output_folder(out)
    except OutputFolderError as exc:
        print(f"error: {exc}. Nothing was written.", file=sys.stderr)
        return None
    return out


def default_folder(scene: object, source: str) -> Path:
    """A run's output folder when ``--out`` is not given: reports/<name>/,
    with the scene's name, else its file's."""
    return Path("reports") / (scene.name or Path(source).stem)


def speed_fraction(text: str) -> float:
    """``--speed``: a playback speed in (0, 10], a fraction of real time."""
    try:
        value = float(text)
    except ValueError:
        value = 0.0
    if not 0.0 < value <= 10.0:
        raise argparse.ArgumentTypeError(f"a fraction of real time in (0, 10], not {text!r}. "
                                         f"Nothing was written")
    return value


def workers_count(text: str) -> int:
    """``--workers``: an integer >= 1."""
    try:
        n = int(text)
    except ValueError:
        n = 0
    if n < 1:
        raise argparse.ArgumentTypeError(
            f"an integer >= 1 (1 runs the cases in this process, one after another; "
            f"leave it out for one worker per core), not {text!r}. Nothing was written")
    return n


def scheduler_url(text: str) -> str:
    """``--scheduler``: a Dask scheduler's address, ``tcp://HOST:PORT``."""
    if "://" not in text:
        raise argparse.ArgumentTypeError(f"a Dask scheduler's address such as "
                                         f"tcp://HOST:8786, not {text!r}. Nothing was written")
    return text
