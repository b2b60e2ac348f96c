"""Loading YAML input files and resolving references between them."""

from __future__ import annotations

from pathlib import Path

import yaml

from design.io.reader import Reader


def _shipped_root() -> Path:
    """Where the shipped ``models/`` and ``problems/`` are: ``design/shipped/``
    in an installed package (setup.py puts them there), else the checkout's
    root beside ``design/`` (an editable install or a clone)."""
    installed = Path(__file__).resolve().parents[1] / "shipped"
    return installed if installed.is_dir() else Path(__file__).resolve().parents[2]


#: the folder holding the shipped models/ and problems/
TOOLKIT_ROOT = _shipped_root()
#: the shipped scene and problem files
PROBLEMS = TOOLKIT_ROOT / "problems"


def find_scene(name: str | Path) -> Path:
    """A scene or problem file as named on the command line: a path from the
    working directory; failing that, a bare name (``hold_time.yaml`` or
    ``hold_time``) among the shipped :data:`PROBLEMS`."""
    path = Path(name)
    if path.exists() or path.name != str(name):
        return path
    for candidate in (PROBLEMS / path.name, PROBLEMS / f"{path.name}.yaml"):
        if candidate.is_file():
            return candidate
    return path


def load_yaml(path: Path, reader: Reader, field: str = "") -> object | None:
    """Parse a YAML file; a missing or malformed file becomes a problem in ``reader``."""
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        reader.add(field, f"cannot read file '{path}': {exc.strerror or exc}")
        return None
    except UnicodeDecodeError as exc:
        reader.add(field, f"not a text file (byte {exc.object[exc.start]:#04x} at offset "
                          f"{exc.start} is not UTF-8); expected a YAML scene, problem or "
                          f"model file")
        return None
    try:
        return yaml.safe_load(text)
    except yaml.reader.ReaderError as exc:            # a character YAML does not allow
        reader.add(field, f"not valid YAML at character {exc.position + 1}: {exc.reason} "
                          f"(code point {exc.character:#x})")
        return None
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


def searched(base_dir: Path) -> str:
    """The folders :func:`resolve` looks in, each named once."""
    above = [base_dir, *base_dir.parents]
    others = [str(f) for f in dict.fromkeys([Path.cwd(), TOOLKIT_ROOT]) if f not in above]
    return ", ".join([f"{base_dir} and the folders above it", *others])


def read_model(reader: Reader, value: object, field: str, base_dir: Path, kind: str, parse):
    """A model given inline (a mapping) or as a path to a model file.

    ``parse(reader, data, field, base_dir, default_name)`` reads the mapping.
    A file's problems are reported under its own name; its own references
    resolve from its folder.
    """
    if isinstance(value, str):
        path = resolve(value, base_dir)
        if path is None:
            reader.add(field, f"{kind} file '{value}' not found (looked in "
                              f"{searched(base_dir)})")
            return None
        sub = Reader(str(path))
        data = load_yaml(path, sub)
        model = None
        if data is not None:
            if isinstance(data, dict) and data.get("kind", kind) != kind:
                sub.add("kind", f"'{data['kind']}' where a {kind} is expected")
            else:
                model = parse(sub, data, "", path.resolve().parent, path.stem)
        for problem in sub.problems:
            reader.record(problem)
        return model
    return parse(reader, value, field, base_dir, "")
