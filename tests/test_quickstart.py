"""examples/quickstart.py as a newcomer runs it: a scene given as a dict
simulated, its time series read, a two-variable design problem solved and
its verdict printed, in seconds."""

import runpy
from pathlib import Path

import design

QUICKSTART = Path(__file__).resolve().parents[1] / "examples" / "quickstart.py"


def test_the_quickstart_simulates_reads_and_solves(capsys):
    result = runpy.run_path(str(QUICKSTART))["main"]()
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].startswith("finished") and "hold" in lines[0]
    assert "recorded instants; the bird's centre rose" in lines[1]
    assert isinstance(result, design.DesignResult) and lines[2] == result.verdict
    assert result.status in (design.Status.VERIFIED, design.Status.NO_IMPROVEMENT)
    assert result.hold_time_s >= result.baseline_hold_time_s
    assert result.max_finger_force_N <= result.cap_N * 1.01
    assert set(result.design) == {"groups.lower.stiffness_scale", "fingers.4.angle"}
    assert lines[3].startswith("optimum: the lower fingers' EI x ") and lines[3].endswith(" deg")
