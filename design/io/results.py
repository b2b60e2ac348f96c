"""Writing results: JSON and CSV, atomically, SI units throughout."""

from __future__ import annotations

import csv
import io
import json
import math
import os
import tempfile
from pathlib import Path

import numpy as np

from design import interrupt


def jsonable(value: object) -> object:
    """numpy arrays and scalars to lists and floats; non-finite floats to None."""
    if isinstance(value, dict):
        return {str(k): jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [jsonable(v) for v in value]
    if isinstance(value, np.ndarray):
        return jsonable(value.tolist())
    if isinstance(value, (np.bool_, bool)):
        return bool(value)
    if isinstance(value, (np.integer,)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        v = float(value)
        return v if math.isfinite(v) else None
    return value


class OutputFolderError(ValueError):
    """A run's output folder cannot be created or written to."""


def check_output_folder(out_dir: Path) -> None:
    """Check, before a run starts, that its files can be written to ``out_dir``.

    The folder, or the nearest folder above it that exists, must be a folder
    in which a file can be created. The probe is an unnamed temporary file:
    nothing is left behind.

    Raises
    ------
    OutputFolderError
        Naming the folder and the reason.
    """
    folder = Path(out_dir).absolute()
    while not folder.exists():
        folder = folder.parent
    if not folder.is_dir():
        raise OutputFolderError(f"output folder '{out_dir}' cannot be created: '{folder}' "
                                f"is a file")
    try:
        with tempfile.TemporaryFile(dir=folder):
            pass
    except OSError as exc:
        raise OutputFolderError(f"output folder '{out_dir}' cannot be written to: "
                                f"{exc.strerror or exc} (creating a file in '{folder}')") from None


def write_atomic_bytes(path: Path, data: bytes) -> None:
    """Write ``data`` to ``path`` through a temporary file and a rename, so
    that an interrupted run leaves the old file or none, never half a file."""
    interrupt.writing()            # from here on, Ctrl-C waits for the run's last file
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
        os.chmod(tmp, 0o666 & ~_umask())         # mkstemp makes it private (0600)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def write_atomic(path: Path, text: str) -> None:
    """Write ``text`` (UTF-8) to ``path`` atomically."""
    write_atomic_bytes(path, text.encode("utf-8"))


def csv_text(rows: list[dict]) -> str:
    """CSV of a list of flat dicts (columns from the first row)."""
    buf = io.StringIO()
    if rows:
        writer = csv.DictWriter(buf, fieldnames=list(rows[0]))
        writer.writeheader()
        for row in rows:
            writer.writerow({k: ("" if v is None else v) for k, v in jsonable(row).items()})
    return buf.getvalue()


def json_text(value: object) -> str:
    """The JSON file of a result: numpy values converted, non-finite numbers
    as null, indented."""
    return json.dumps(jsonable(value), indent=1, allow_nan=False) + "\n"


def write_texts(out_dir: Path, files: dict[str, str]) -> list[Path]:
    """Write each rendered file (name -> text) atomically; returns the paths."""
    for name, text in files.items():
        write_atomic(out_dir / name, text)
    return [out_dir / name for name in files]


def output_files(result: dict, tables: dict[str, list[dict]],
                 texts: dict[str, str] | None = None) -> dict[str, str]:
    """A run's files rendered in memory (name -> text): ``result.json``, each
    CSV table and further text files, so that an error leaves no partial file."""
    files = {"result.json": json_text(result)}
    files.update({name: csv_text(rows) for name, rows in tables.items()})
    files.update(texts or {})
    return files


#: the list of files the last run wrote to its output folder, one relative path a line
MANIFEST = ".design-outputs"


def record_outputs(out_dir: Path, written: list[Path]) -> list[Path]:
    """Record the files a run wrote in ``out_dir`` and delete those that the
    previous run there wrote and this one did not (another kind of scene's
    ``timeseries.csv`` or figures), so that the folder holds one run's results.

    Files the toolkit did not write are never touched. Returns the paths deleted.
    """
    manifest = out_dir / MANIFEST
    names = [p.relative_to(out_dir).as_posix() for p in written]
    stale = [out_dir / name for name in _recorded(manifest) if name not in names]
    for path in stale:
        if path.is_file():
            path.unlink()
        folder = path.parent
        if folder != out_dir and folder.is_dir() and not any(folder.iterdir()):
            folder.rmdir()
    write_atomic(manifest, "".join(f"{name}\n" for name in names))
    return stale


def _recorded(manifest: Path) -> list[str]:
    """The relative paths in a manifest; none from an unreadable one, and
    none that could point outside its folder."""
    try:
        lines = manifest.read_text(encoding="utf-8").splitlines()
    except (OSError, UnicodeDecodeError):
        return []
    return [line for line in lines
            if line and not Path(line).is_absolute() and ".." not in Path(line).parts
            and line != MANIFEST]
