"""Reading any input file: dispatch on its ``kind``, collect every problem.

Scene kinds are simulated by ``design simulate``; model kinds (``finger``)
can be checked on their own by ``design check``.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import yaml

from design.io.beam_scene import read_beam
from design.io.contact_scene import read_contact
from design.io.design_problem import read_design
from design.io.grasp_scene import MODEL_READERS, read_grasp
from design.io.fingers import read_finger
from design.io.files import PROBLEMS, find_scene, load_yaml
from design.io.fit_problem import read_fit
from design.io.reader import Reader, did_you_mean

#: kind -> (required top-level keys, optional top-level keys, reader)
KINDS = {
    "beam": (("finger", "load"), ("solver",), read_beam),
    "contact": (("finger", "drum", "finger_angle", "object", "friction"),
                ("sliding", "motion", "solver"), read_contact),
    "grasp": (("grasper", "bird", "conveyor", "drum_speed", "start", "duration"),
              ("finger_models", "mounts", "friction", "legs", "finger_model", "solver", "belt"),
              read_grasp),
    "design": (("scene", "variables"), ("cap", "rules", "solver", "population",
                                         "multistart", "model_check", "robustness",
                                         "objective", "min_hold", "finger_sets"),
               read_design),
}
MODEL_KINDS = ("finger", *MODEL_READERS)
_COMMON = ("kind", "name", "description")


def load_scene(source: str | Path | Mapping) -> object:
    """Read and validate a scene file (path) or its content (mapping).

    Returns the kind's settings object (e.g. :class:`~design.io.beam_scene.BeamScene`).

    Raises
    ------
    ProblemFileError
        With every problem found, each naming the file and the field.
    """
    reader, data, base_dir, name = _open(source)
    scene = None
    if data is not None and data.get("kind") == "fit":
        reader.add("kind", "'fit' is a fit problem: run it with 'design fit'")
        data = None
    if data is not None:
        kind = reader.choice(data, "kind", "", list(KINDS))
        if kind is not None:
            required, optional, read = KINDS[kind]
            reader.mapping(data, "", required=required, optional=(*optional, *_COMMON))
            reader.text(data, "name", "", default=name)
            reader.text(data, "description", "", default="")
            scene = read(reader, data, base_dir, data.get("name", name))
    reader.raise_if_any()
    return scene


def check_file(source: str | Path | Mapping) -> tuple[str, object]:
    """Validate any input file, scene, problem or model: its kind and what
    it describes; raises :class:`ProblemFileError` with every problem found."""
    reader, data, base_dir, name = _open(source)
    if isinstance(data, Mapping) and data.get("kind") == "fit":
        return "fit", load_fit(source)
    if isinstance(data, Mapping) and data.get("kind") in MODEL_KINDS:
        kind = data["kind"]
        if kind == "finger":
            model = read_finger(reader, dict(data), "", base_dir)
        else:
            model = MODEL_READERS[kind](reader, dict(data), "", base_dir, name)
        reader.raise_if_any()
        return kind, model
    reader.raise_if_any()
    scene = load_scene(source)
    return data["kind"], scene


def load_fit(source: str | Path | Mapping) -> object:
    """Read and validate a fit problem (``kind: fit``) and its data file;
    raises :class:`ProblemFileError` with every problem found."""
    reader, data, base_dir, name = _open(source)
    problem = None
    if data is not None:
        if data.get("kind") != "fit":
            reader.add("kind", f"{data.get('kind')!r} where a fit problem (kind: fit) is "
                               f"expected; 'design simulate' runs scenes")
        else:
            problem = read_fit(reader, data, base_dir, name)
    reader.raise_if_any()
    return problem


def examples() -> list[tuple[Path, str, str]]:
    """The shipped problems, by file name: (file, kind, the first sentence of
    its description)."""
    found = []
    for path in sorted(PROBLEMS.glob("*.yaml")):
        data = yaml.safe_load(path.read_text(encoding="utf-8"))
        summary = " ".join(data.get("description", "").split()).split(". ")[0].rstrip(".")
        found.append((path, data["kind"], summary + "."))
    return found


def _open(source: str | Path | Mapping) -> tuple[Reader, dict | None, Path, str]:
    if isinstance(source, Mapping):
        return Reader("<scene>"), dict(source), Path.cwd(), "scene"
    path = find_scene(source)
    reader = Reader(str(path))
    if not path.exists() and path.name == str(source):      # a bare name, found nowhere
        shipped = [p.name for p in PROBLEMS.glob("*.yaml")]
        reader.add("", f"no such file in {Path.cwd()} nor among the shipped problems "
                       f"({PROBLEMS}; 'design examples' lists them)"
                       f"{did_you_mean(path.name, shipped)}")
        return reader, None, Path.cwd(), path.stem
    data = load_yaml(path, reader)
    if data is None and reader.ok:
        reader.add("", "the file is empty")
    elif data is not None and not isinstance(data, Mapping):
        reader.mapping(data, "")
        data = None
    return reader, data, path.resolve().parent, path.stem
