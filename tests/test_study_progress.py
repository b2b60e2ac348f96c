"""A study's progress off a terminal: one line per finished case with the
best verified hold, a summary table at the end; quiet shows nothing."""

import io

from design.study import Case, StudyOptions, StudyProgress, run_study
from design.study.progress import RATE

CASES = [Case("a", {"hold": 0.2, "verified": True}), Case("b", {"hold": 0.5, "verified": False}),
         Case("c", {"hold": 0.3, "verified": True}, after="a")]


def held(case, upstream):
    """A hold as the inputs say; verified or not."""
    return {"status": "verified" if case.inputs["verified"] else "failed verification",
            "hold_time_s": case.inputs["hold"], "verified": case.inputs["verified"]}


def shown(quiet: bool = False) -> str:
    stream = io.StringIO()
    run_study(CASES, held, options=StudyOptions(workers=1), label="hold_time",
              progress=StudyProgress(quiet=quiet, stream=stream))
    return stream.getvalue()


def test_each_finished_case_is_a_line_with_the_best_verified_hold_so_far():
    lines = shown().splitlines()
    assert lines[0] == "hold_time: 3 cases; running on this process, one case after another"
    assert lines[1].startswith("a: verified, hold 0.2000 s; hold_time: cases 1/3, best "
                               "verified hold 0.2000 s, elapsed ")
    # b's longer hold is not verified: the best stays a's
    assert lines[2].startswith("b: failed verification, hold 0.5000 s; hold_time: cases 2/3, "
                               "best verified hold 0.2000 s")
    assert "left" in lines[2]
    assert lines[3].startswith("c: verified, hold 0.3000 s; hold_time: cases 3/3, best "
                               "verified hold 0.3000 s") and lines[3].endswith("done")


def test_the_summary_table_has_every_case():
    table = shown().split("done\n", 3)[-1]
    for header in ("key", "status", "hold (s)", "wall time (s)", "worker"):
        assert header in table
    rows = [line for line in table.splitlines() if line.startswith("│")]
    assert [row.split("│")[1].strip() for row in rows] == ["a", "b", "c"]
    assert "failed verification" in rows[1] and "0.5000" in rows[1]


def test_quiet_shows_nothing():
    assert shown(quiet=True) == ""


def rated(case, upstream):
    """A line rate and worst hold as the inputs say; verified or not."""
    return {**held(case, upstream), "line_rate_per_min": case.inputs["rate"]}


def test_a_line_study_shows_the_best_verified_rate():
    """A throughput study's line gives the best verified rate (birds/min),
    not the longest hold; an unverified faster case is not the best."""
    cases = [Case("sets-3", {"hold": 0.3, "verified": True, "rate": 90.0}),
             Case("sets-4", {"hold": 0.2, "verified": False, "rate": 120.0}),
             Case("sets-5", {"hold": 0.21, "verified": True, "rate": 100.0})]
    stream = io.StringIO()
    run_study(cases, rated, options=StudyOptions(workers=1), label="line",
              progress=StudyProgress(stream=stream, goal=RATE))
    lines = stream.getvalue().splitlines()
    assert lines[1].startswith("sets-3: verified, 90.0 birds/min, hold 0.3000 s; line: cases "
                               "1/3, best verified rate 90.0 birds/min")
    assert "best verified rate 90.0 birds/min" in lines[2]
    assert "best verified rate 100.0 birds/min" in lines[3]
    assert "rate (birds/min)" in stream.getvalue()
