"""Collocation sweeps: the condensed and the sparse Newton step are the full
system's, the compiled sweep computes what the interpreted one does, a
chain that runs out of Newton steps hands its loads to the one-by-one
solve, and a sweep's shape table is every case's every point."""

from pathlib import Path

import casadi as ca
import numpy as np
import pytest

from design.physics.beam import PointLoad
from design.physics.stiffness import UniformEI
from design.solvers import compiled as comp
from design.solvers.beam import collocation, solve_beam, sweep
from design.solvers.beam.collocation import BeamTranscription
from tests.problems import table_2_3, thesis_finger, tip_distance

ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.parametrize("stiffness", [thesis_finger().stiffness, UniformEI(0.08)])
@pytest.mark.parametrize("intervals, degree", [(16, 4), (5, 3), (3, 1)])
def test_both_newton_steps_are_the_whole_systems(stiffness, intervals, degree):
    tr = BeamTranscription(stiffness, intervals, degree)
    rng = np.random.default_rng(intervals)
    widths = rng.dirichlet(np.ones(intervals))                   # a graded mesh
    P = np.concatenate([[20.0, 1.2, 0.0762, 0.05], widths, stiffness.params])
    w = 0.3 * rng.normal(size=tr.n_w)                            # far from the solution
    ws, ps = ca.SX.sym("w", tr.n_w), ca.SX.sym("P", tr.n_p)
    jac = ca.Function("jacobian", [ws, ps], [ca.jacobian(tr.residual(ws, ps), ws)])
    newton = w - np.linalg.solve(np.asarray(jac(w, P)), np.asarray(tr.residual(w, P)).ravel())
    # a far, random point: rounding grows with the Jacobian's condition (up to 3e5 here)
    for step in (tr.newton_step, sweep.sparse_newton_step(tr)):     # compiled / interpreted
        got = np.asarray(step(w, P)).ravel()
        assert np.max(np.abs(got - newton)) <= 1e-11 * np.max(np.abs(newton - w))


@pytest.fixture
def fresh(monkeypatch):
    """No transcription (with its sweep functions) built yet."""
    monkeypatch.setattr(collocation, "_TRANSCRIPTIONS", {})


def sweep_loads(n):
    finger, load = table_2_3()
    return finger, [PointLoad(f, 1.2, load.at) for f in np.linspace(0.5, 30.0, n)]


@pytest.mark.skipif(comp.compiler()[0] is None, reason="no C compiler")
def test_compiled_sweep_computes_what_the_interpreted_one_does(fresh, monkeypatch):
    finger, loads = sweep_loads(40)
    monkeypatch.setattr(sweep, "COMPILE_MIN_LOADS", 10)
    fast = solve_beam(finger, loads, "collocation", nodes=4, degree=2)
    assert "beam_continuation_step" in comp.status.libraries[-1]["functions"]
    monkeypatch.setattr(sweep, "COMPILE_MIN_LOADS", 10 ** 9)
    slow = solve_beam(finger, loads, "collocation", nodes=4, degree=2)
    assert all(a.converged and b.converged for a, b in zip(fast, slow))
    assert [a.iterations for a in fast] == [b.iterations for b in slow]
    assert max(tip_distance(a, b) for a, b in zip(fast, slow)) < 1e-15
    np.testing.assert_allclose([a.error_estimate for a in fast],
                               [b.error_estimate for b in slow], rtol=1e-9)


def test_a_chain_out_of_newton_steps_leaves_its_loads_to_single_solves(fresh, monkeypatch):
    finger, loads = sweep_loads(6)                 # 6 N apart: a start one step cannot finish
    chained = solve_beam(finger, loads, "collocation")
    assert all(s.converged and s.iterations >= 1 for s in chained)
    assert max(s.iterations for s in chained) >= 2
    monkeypatch.setattr(collocation, "_TRANSCRIPTIONS", {})
    monkeypatch.setattr(sweep, "MAX_STEPS", 1)
    redone = solve_beam(finger, loads, "collocation")
    assert all(s.converged for s in redone)
    assert any(s.iterations > 1 for s in redone)   # solved one by one, from the seed
    for a, b in zip(chained, redone):
        assert tip_distance(a, b) <= a.error_estimate + b.error_estimate


def test_a_sweeps_shape_table_has_every_case_and_point():
    """shapes.csv's rows are made when read: the same rows, in order, as
    the result's shapes, each finger run on to its free end."""
    import design
    from design.run.beam import ShapeRows

    finger = ROOT / "models" / "fingers" / "thesis_nonuniform_soft.yaml"
    result = design.simulate({"kind": "beam", "finger": str(finger),
                              "load": {"F": [0, 5, 10, 15, 20], "alpha": "60 deg", "at": 0.1}}
                             ).to_dict()
    rows = ShapeRows(result["cases"])
    expected = [{"case": i, "s_m": s, "x_m": x, "y_m": y, "psi_rad": p, "M_N_m": m}
                for i, c in enumerate(result["cases"])
                for s, x, y, p, m in zip(*(c["shape"][k] for k in ("s", "x", "y", "psi", "M")))]
    assert len(rows) == len(expected) and list(rows) == expected
    assert [rows[i] for i in (0, 7, -1)] == [expected[i] for i in (0, 7, -1)]
    assert all(c["shape"]["s"][-1] == 0.203 and c["shape"]["s"].size == c["shape"]["x"].size
               for c in result["cases"])
