"""``design animate RESULT_DIR``: a grasp or design run's animation on its
own, from its result.json alone: MP4 (ffmpeg) or GIF, or the interactive
HTML view.

The result keeps the bird's state at every frame and each run's scene
(its ``animation`` entry); the fingers are not kept, so their contacts are
solved again at those states, as the report does.
"""

from __future__ import annotations

import json
import tempfile
from pathlib import Path

from design.errors import ProblemFileError

#: the files ``--out`` may name, by suffix
FORMATS = (".mp4", ".gif", ".html")


class AnimateError(ValueError):
    """A result that cannot be animated, or an output that cannot be written:
    the message names the file and the field."""


def read_record(result_dir: Path) -> tuple[dict, Path]:
    """The result in ``result_dir`` (its result.json) and that file's path;
    raises :class:`AnimateError` if it is missing, unreadable or holds no
    animation (a beam or contact run)."""
    path = Path(result_dir) / "result.json"
    try:
        result = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise AnimateError(f"{path}: no such file (RESULT_DIR is a run's output folder)") \
            from None
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise AnimateError(f"{path}: cannot be read as JSON: {exc}") from None
    if not isinstance(result, dict) or result.get("kind") not in ("grasp", "design"):
        kind = result.get("kind") if isinstance(result, dict) else None
        raise AnimateError(f"{path}: kind: {kind!r} has no animation (grasp and design runs "
                           f"have)")
    record = result.get("animation")
    if not isinstance(record, dict) or not isinstance(record.get("runs"), dict):
        raise AnimateError(f"{path}: animation: missing; run the scene again to write it")
    return result, path


def output_path(result_dir: Path, out: str | None, ffmpeg: bool) -> Path:
    """Where to write: ``out`` (its suffix the format), else
    RESULT_DIR/animation.mp4 with ffmpeg, animation.gif without."""
    if out is None:
        return Path(result_dir) / ("animation.mp4" if ffmpeg else "animation.gif")
    path = Path(out)
    if path.suffix not in FORMATS:
        raise AnimateError(f"--out {out}: the file's suffix names the format: "
                           f"{', '.join(FORMATS)}")
    if path.suffix == ".mp4" and not ffmpeg:
        raise AnimateError(f"--out {out}: MP4 needs ffmpeg, which is not installed; "
                           f"write .gif or .html instead")
    if path.parent.exists() and not path.parent.is_dir():
        raise AnimateError(f"--out {out}: '{path.parent}' is not a folder")
    return path


def animate(result_dir: str | Path, out: str | Path | None = None, speed: float = 0.25,
            progress=None) -> Path:
    """Write the animation of the run in ``result_dir`` (see the module);
    returns the file written. ``speed``: a video's playback speed, a
    fraction of real time. Raises :class:`AnimateError` (nothing written)."""
    from design.io.results import write_atomic, write_atomic_bytes
    from design.report.animation import animated_runs
    from design.report.grasp import animation_view
    from design.report.page import Page
    from design.report.video import ffmpeg_available, write_video
    from design.solvers.grasp.fingers import ContactFailed

    result, source = read_record(Path(result_dir))
    path = output_path(Path(result_dir), None if out is None else str(out), ffmpeg_available())
    record = result["animation"]
    try:
        runs = animated_runs(record)
    except ProblemFileError as exc:
        raise AnimateError(f"{source}: animation.runs: scene: " + "; ".join(exc.problems)) \
            from None
    except ContactFailed as exc:
        raise AnimateError(f"{source}: animation: {exc}") from None
    if progress:
        frames = ", ".join(f"{r.label} {len(r.frames)}" for r in runs)
        progress(f"finger shapes solved again at the frame states stored in {source} "
                 f"({frames} frames); writing {path.suffix[1:].upper()}")
    path.parent.mkdir(parents=True, exist_ok=True)
    if path.suffix == ".html":
        page = Page(f"Animation: {result.get('name', '')}")
        animation_view(page, runs, record)
        write_atomic(path, page.render())
        return path
    with tempfile.TemporaryDirectory(dir=path.parent) as tmp:
        partial = Path(tmp) / f"animation{path.suffix}"
        write_video(runs, record["frame_step_s"], record["cap_N"], partial, speed)
        write_atomic_bytes(path, partial.read_bytes())
    return path
