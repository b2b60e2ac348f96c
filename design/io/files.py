"""Loading YAML input files and resolving references between them."""

from __future__ import annotations

from pathlib import Path

import yaml

from design.io.reader import Reader

#: the folder holding design/, models/ and problems/ in a checkout
TOOLKIT_ROOT = Path(__file__).resolve().parents[2]


def load_yaml(path: Path, reader: Reader, field: str = "") -> object | None:
    """Parse a YAML file; a missing or malformed file becomes a problem in ``reader``."""
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        reader.add(field, f"cannot read file '{path}': {exc.strerror or exc}")
        return None
    try:
        return yaml.safe_load(text)
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f" at line {mark.line + 1}, column {mark.column + 1}" if mark else ""
        reader.add(field, f"not valid YAML{where}: {getattr(exc, 'problem', exc)}")
        return None


def resolve(reference: str, base_dir: Path) -> Path | None:
    """Find a referenced model file.

    Tried in order: relative to the referring file's folder and each of its
    parents (so ``models/fingers/x.yaml`` works from ``problems/``), the
    working directory, then the toolkit's own checkout (which holds the
    shipped ``models/``). Returns None when nothing exists.
    """
    ref = Path(reference)
    if ref.is_absolute():
        return ref if ref.is_file() else None
    for folder in [base_dir, *base_dir.parents, Path.cwd(), TOOLKIT_ROOT]:
        candidate = folder / ref
        if candidate.is_file():
            return candidate
    return None
