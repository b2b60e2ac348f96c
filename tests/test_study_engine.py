"""design.study in this process (workers=1): order and chains, failed and
skipped cases, the JSON round trip, resume after a stop, and no Dask."""

import functools
import os
import socket
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from design.errors import Interrupted
from design.study import Case, StudyOptions, StudyProgress, run_study
from design.study.cases import ordered
from design.study.engine import ENGINE_KEYS
from design.study.store import read_cases
from tests.study_tasks import called, interrupted, value

ROOT = Path(__file__).resolve().parents[1]
SERIAL = StudyOptions(workers=1)

#: two chains given downstream first, a case on its own, a failing case and
#: the chain after it, a case that needs two and one that needs the failing one too
CASES = [Case("b2", {"x": 4}, after="b1"), Case("b1", {"x": 3}, after="a"), Case("a", {"x": 1}),
         Case("c", {"x": 2}), Case("bad", {"x": 5, "fail": True}),
         Case("after-bad", {"x": 6}, after="bad"), Case("after-after-bad", {"x": 7},
                                                         after="after-bad"),
         Case("joined", {"x": 8}, after=("b2", "a")),
         Case("after-c-and-bad", {"x": 9}, after=("c", "bad"))]


def task(folder: Path):
    calls = folder / "calls"
    calls.mkdir(parents=True, exist_ok=True)
    return functools.partial(value, calls), calls


def stripped(results: dict) -> dict:
    """The results without the engine's wall time and worker."""
    return {key: {k: v for k, v in r.items() if k not in ENGINE_KEYS}
            for key, r in results.items()}


class StopAfter(StudyProgress):
    """Ctrl-C pressed as the ``k``-th case finishes (it is in the store then)."""

    def __init__(self, k: int):
        super().__init__(quiet=True)
        self.k = k

    def finished(self, key, result):
        super().finished(key, result)
        if self.done == self.k:
            raise Interrupted(f"after {self.k} cases (simulated Ctrl-C)")


def test_each_case_runs_after_the_case_it_needs_and_gets_its_result(tmp_path):
    fn, calls = task(tmp_path)
    results = run_study(CASES, fn, options=SERIAL, label="t")
    assert list(results) == [c.key for c in CASES]           # the caller's order
    assert results["b2"]["chain"] == ["a", "b1", "b2"]
    assert results["b2"]["hold_time_s"] == pytest.approx(0.08)
    assert results["c"]["chain"] == ["c"]
    assert [c.key for c in ordered(CASES)][:3] == ["a", "b1", "b2"]
    # a case that needs several gets each result, in the order it names them
    assert results["joined"]["chain"] == ["a", "b1", "b2", "a", "joined"]
    assert results["joined"]["hold_time_s"] == pytest.approx(0.08 + 0.01 + 0.08)
    assert ordered(CASES).index(CASES[-2]) > max(ordered(CASES).index(c) for c in CASES[:3])
    here = f"{socket.gethostname()}:{os.getpid()}"
    assert {r["worker"] for k, r in results.items() if not k.startswith("after-")} == {here}
    assert all(r["wall_time_s"] >= 0.005 for k, r in results.items() if not k.startswith("after-"))


def test_a_failed_case_is_recorded_and_the_cases_after_it_skipped(tmp_path, capsys):
    fn, calls = task(tmp_path)
    results = run_study(CASES, fn, options=StudyOptions(workers=1, store=tmp_path / "s.sqlite"),
                        label="t")
    assert results["bad"]["status"] == "error"
    assert results["bad"]["message"] == "ValueError: case bad fails on purpose"
    assert results["after-bad"]["status"] == "skipped"
    assert "'bad'" in results["after-bad"]["message"]
    assert results["after-after-bad"]["status"] == "skipped"
    assert "'after-bad'" in results["after-after-bad"]["message"]
    assert "after-bad" not in called(calls) and "after-after-bad" not in called(calls)
    assert results["after-c-and-bad"]["status"] == "skipped"
    assert "'bad'" in results["after-c-and-bad"]["message"]
    assert "after-c-and-bad" not in called(calls)
    assert all(results[k]["status"] == "verified" for k in ("a", "b1", "b2", "c", "joined"))
    err = capsys.readouterr().err
    assert err.count("Traceback") == 1 and "fails on purpose" in err
    assert not any("Traceback" in str(r) for r in results.values())
    stored = {row["key"]: row for row in read_cases(tmp_path / "s.sqlite")}
    assert stored["bad"]["status"] == "error" and stored["after-bad"]["status"] == "skipped"
    assert stored["bad"]["message"] == results["bad"]["message"]


@pytest.mark.parametrize("cases, named", [
    ([Case("a", {}, after="nobody")], "'a'"),
    ([Case("a", {}, after="b"), Case("b", {}, after="a")], "cycle"),
    ([Case("a", {}, after=("c", "b")), Case("b", {}, after="a"), Case("c", {})],
     "cycle: a -> b -> a"),
    ([Case("a", {}, after=("b", "nobody")), Case("b", {})], "'nobody'"),
    ([Case("a", {}), Case("a", {})], "'a' is given twice"),
    ([Case("a", {"x": object()})], "'a': inputs are not JSON"),
])
def test_bad_case_lists_are_refused_by_name(cases, named, tmp_path):
    fn, calls = task(tmp_path)
    with pytest.raises(ValueError, match=named):
        run_study(cases, fn, options=SERIAL, label="t")
    assert called(calls) == []


def test_results_are_json_and_equal_to_what_the_store_holds(tmp_path):
    store = tmp_path / "s.sqlite"
    results = run_study([Case("n", {"x": np.float64(2.0)})], numpy_task,
                        options=StudyOptions(workers=1, store=store), label="t")
    assert results["n"]["values"] == [1.0, None] and type(results["n"]["count"]) is int
    assert read_cases(store)[0]["hold_time_s"] == results["n"]["hold_time_s"] == 0.5


def numpy_task(case, upstream):
    return {"status": "verified", "values": np.array([1.0, np.nan]), "count": np.int64(3),
            "hold_time_s": np.float64(0.5)}


def test_a_stopped_study_resumes_with_only_the_cases_left(tmp_path):
    fn, calls = task(tmp_path / "stopped")
    store = tmp_path / "cases.sqlite"
    with pytest.raises(Interrupted):
        run_study(CASES, fn, options=StudyOptions(workers=1, store=store), label="t",
                  progress=StopAfter(3))
    assert [row["key"] for row in read_cases(store)] == ["a", "b1", "b2"] == called(calls)
    again, calls_again = task(tmp_path / "resumed")
    resumed = run_study(CASES, again, options=StudyOptions(workers=1, store=store, resume=True),
                        label="t")
    # the rest; bad's downstream are skipped
    assert called(calls_again) == ["bad", "c", "joined"]
    whole = run_study(CASES, task(tmp_path / "whole")[0], options=SERIAL, label="t")
    assert stripped(resumed) == stripped(whole)
    assert len(read_cases(store)) == len(CASES)


def test_ctrl_c_inside_a_case_keeps_the_finished_ones(tmp_path):
    store = tmp_path / "cases.sqlite"
    calls = tmp_path / "calls"
    calls.mkdir()
    with pytest.raises(Interrupted, match="in case c"):
        run_study(CASES, functools.partial(interrupted, calls, at="c"),
                  options=StudyOptions(workers=1, store=store), label="t")
    assert [row["key"] for row in read_cases(store)] == ["a", "b1", "b2"]


def test_resume_runs_again_failed_cases_and_those_whose_inputs_changed(tmp_path):
    store = tmp_path / "cases.sqlite"
    run_study(CASES, task(tmp_path / "first")[0],
              options=StudyOptions(workers=1, store=store), label="t")
    changed = [Case(c.key, {**c.inputs, "x": 9}, c.after) if c.key == "b1" else
               Case(c.key, {"x": 5}) if c.key == "bad" else c for c in CASES]
    fn, calls = task(tmp_path / "second")
    results = run_study(changed, fn, options=StudyOptions(workers=1, store=store, resume=True),
                        label="t")
    # b1's inputs changed, so b2, which warm-starts from it, is not reused
    # either, nor joined, which needs b2
    assert called(calls) == sorted(["b1", "b2", "bad", "after-bad", "after-after-bad",
                                    "joined", "after-c-and-bad"])
    assert results["b2"]["hold_time_s"] == pytest.approx(0.14)
    assert results["after-after-bad"]["status"] == "verified"


def test_a_study_in_this_process_does_not_import_dask(tmp_path):
    code = ("import functools, sys\nfrom pathlib import Path\n"
            "from design.study import Case, StudyOptions, run_study\n"
            "from tests.study_tasks import value\n"
            f"calls = Path({str(tmp_path)!r})\n"
            "r = run_study([Case('a', {'x': 1}), Case('b', {'x': 2}, after='a')],"
            " functools.partial(value, calls), options=StudyOptions(workers=1), label='t')\n"
            "assert r['b']['chain'] == ['a', 'b'], r\n"
            "print(sorted(m for m in sys.modules if m.split('.')[0] in ('dask', 'distributed')))")
    done = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True,
                          timeout=60)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "[]"
