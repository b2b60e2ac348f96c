"""Property-based tests over scene inputs: any generated scene file
either is accepted (and would run) or is rejected with exit status 2, every
problem printed as `error: file: ...` and nothing written; never a traceback.

Scenes are generated three ways: arbitrary YAML documents, the shipped
problems (their models inlined) with one value replaced, removed or its key
renamed, and arbitrary bytes. The runners are replaced by a stub so that only
reading and validation run (each example takes milliseconds).
"""

import contextlib
import io
import tempfile
from pathlib import Path
from unittest import mock

import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from design.api import RUNNERS
from design.cli import main

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = settings(max_examples=20, deadline=None, derandomize=True,
                    suppress_health_check=[HealthCheck.too_slow])


def inline(value: object, folder: Path) -> object:
    """``value`` with every reference to a shipped YAML file replaced by the
    file's content (recursively), so that mutations reach the models too."""
    if isinstance(value, str) and value.endswith(".yaml"):
        for base in (folder, ROOT):
            path = (base / value).resolve()
            if path.is_file():
                return inline(yaml.safe_load(path.read_text()), path.parent)
        return value
    if isinstance(value, dict):
        return {k: inline(v, folder) for k, v in value.items()}
    if isinstance(value, list):
        return [inline(v, folder) for v in value]
    return value


SHIPPED = {p.name: inline(yaml.safe_load(p.read_text()), p.parent)
           for p in sorted((ROOT / "problems").glob("*.yaml"))}


def keys_of(value: object) -> set[str]:
    if isinstance(value, dict):
        return set(map(str, value)).union(*map(keys_of, value.values()))
    if isinstance(value, list):
        return set().union(*map(keys_of, value)) if value else set()
    return set()


#: every key the shipped files use, so generated mappings hit real fields
KEYS = sorted(set().union(*map(keys_of, SHIPPED.values())))
SCALARS = (st.none() | st.booleans() | st.integers(-10**9, 10**9) | st.floats()
           | st.text(max_size=10)
           | st.sampled_from(["90 deg", "4 in", "-3 mm", "1e400", "nan", "inf N", "4.8 MPa",
                              "20 rpm", "0.08 N m^2", "", "models/fingers/none.yaml",
                              "design", "beam", "grasp", "contact", "planar", "spatial"]))
VALUES = st.recursive(SCALARS, lambda inner: st.lists(inner, max_size=4) | st.dictionaries(
    st.sampled_from(KEYS) | st.text(max_size=6), inner, max_size=4), max_leaves=10)


def places(value: object, path: tuple = ()):
    """Every (container path, key) in a nested document."""
    items = value.items() if isinstance(value, dict) else (
        enumerate(value) if isinstance(value, list) else ())
    for key, child in items:
        yield path, key
        yield from places(child, (*path, key))


def at(document: object, path: tuple) -> object:
    for key in path:
        document = document[key]
    return document


@st.composite
def mutated_problems(draw) -> dict:
    """A shipped problem (models inlined) with one value replaced, one key
    removed or one key renamed."""
    document = yaml.safe_load(yaml.safe_dump(SHIPPED[draw(st.sampled_from(sorted(SHIPPED)))]))
    path, key = draw(st.sampled_from(list(places(document))))
    container = at(document, path)
    change = draw(st.sampled_from(["replace", "remove", "rename"]))
    if change == "replace" or isinstance(container, list):
        container[key] = draw(VALUES)
    elif change == "remove":
        del container[key]
    else:
        container[draw(st.sampled_from(KEYS) | st.text(max_size=6))] = container.pop(key)
    return document


def run(content: bytes) -> None:
    """The property, for one file: `design check` exits 0 or 2; `design
    simulate` / `design solve` either reaches its runner or exits 2 with
    every problem printed and nothing written; the two agree."""
    with tempfile.TemporaryDirectory() as folder:
        scene, out = Path(folder) / "scene.yaml", Path(folder) / "out"
        scene.write_bytes(content)
        checked = _quiet(["check", str(scene)])
        try:
            data = yaml.safe_load(content.decode("utf-8"))
        except (UnicodeDecodeError, yaml.YAMLError):
            data = None
        command = "solve" if isinstance(data, dict) and data.get("kind") == "design" else "simulate"
        ran = object()
        stub = {kind: mock.Mock(side_effect=StopIteration(ran)) for kind in RUNNERS}
        with mock.patch.dict(RUNNERS, stub):
            try:
                status, err = _quiet([command, str(scene), "--out", str(out), "--quiet"])
            except StopIteration as stop:
                assert stop.value is ran
                status, err = 0, ""
        assert checked[0] in (0, 2), checked
        if status == 2:
            assert not out.exists()
            lines = err.splitlines()
            assert lines and all(line.startswith("error: ") for line in lines[:-1]), err
            assert lines[-1].lower().endswith("nothing was written."), err
        if checked[0] == 2:
            assert status == 2 and f"error: {scene}" in checked[1], (checked, err)
        else:
            is_model = isinstance(data, dict) and data.get("kind") not in (
                "beam", "contact", "grasp", "design")
            assert status == 0 or is_model, err


def _quiet(argv: list[str]) -> tuple[int, str]:
    """Run the command with its output captured: (exit status, stderr)."""
    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        status = main(argv)
    return status, err.getvalue()


def test_the_shipped_problems_with_their_models_inlined_are_valid():
    """The starting points of the mutations are accepted as they are."""
    for name, document in SHIPPED.items():
        run(yaml.safe_dump(document).encode())


@EXAMPLES
@given(mutated_problems())
def test_a_changed_shipped_problem_runs_or_is_rejected_cleanly(document):
    run(yaml.safe_dump(document, allow_unicode=True).encode())


@EXAMPLES
@given(st.sampled_from(["beam", "contact", "grasp", "design", "finger", None]),
       st.dictionaries(st.sampled_from(KEYS) | st.text(max_size=6), VALUES, max_size=6))
def test_any_yaml_document_runs_or_is_rejected_cleanly(kind, fields):
    document = fields if kind is None else {"kind": kind, **fields}
    run(yaml.safe_dump(document, allow_unicode=True).encode())


@EXAMPLES
@given(st.binary(max_size=64) | st.text(max_size=40).map(str.encode))
def test_any_bytes_run_or_are_rejected_cleanly(content):
    run(content)
