"""The optimiser's spatial finger (design/solvers/optimize/finger_load.py's
SpatialStage) against the simulator's (design/solvers/grasp/fingers.py's
SpatialFinger): the same contact, load and force from the same state, and
its explicit Jacobian is CasADi's derivative of the same chain; and the
design NLP calls it with each node's whole state (the rates set the
friction), its time and the design."""

import re
from dataclasses import replace
from pathlib import Path

import casadi as ca
import numpy as np
import pytest

from design.io.scene import load_scene
from design.run.solve import design_space
from design.solvers.contact.spatial import SpatialState
from design.solvers.grasp.fingers import FingerForces, SpatialFinger
from design.solvers.grasp.integrate import IntegratorSettings
from design.solvers.grasp.simulation import SPATIAL_NODES, simulate_grasp
from design.solvers.optimize.schedule import STAGES, schedule_of
from design.solvers.optimize.transcription import DesignNLP, NLPSettings
from design.solvers.optimize.trust_region import LOOP_SIMULATOR
from design.solvers.optimize.variables import DesignSpace, parameters_of
from tests import prefetch

ROOT = Path(__file__).resolve().parents[1]
#: the prefetch worker's keys for :func:`placed_hold` and :func:`on_the_belt`
PLACED_HOLD = "test_spatial_nlp: placed bird, 0.5 s"
ON_THE_BELT = "test_spatial_nlp: placed bird, 0.245 s, at the design loop's tolerance"


def placed_space(duration: float) -> DesignSpace:
    """The main problem's design space with the spatial finger, cut to ``duration`` s."""
    space = design_space(load_scene(ROOT / "problems" / "hold_time_planar.yaml"))
    return DesignSpace(replace(space.baseline, duration=duration, finger_model="spatial"),
                       space.variables)


def placed_hold():
    """The spatial placed bird over 0.5 s at the scene's default tolerances
    (3.5 s CPU, 9.3 s at the design loop's): its hold window [0, 0.44 s]
    ends in a touch-down, so the optimiser can schedule it."""
    space = placed_space(0.5)
    return simulate_grasp(space.setup(space.scale(space.base_values)), IntegratorSettings(),
                          SPATIAL_NODES)


@pytest.fixture(scope="module")
def placed():
    """The main problem's scene with the spatial finger, 0.04 s of it (0.6 s
    CPU): finger 4a presses the placed mean bird about 14 N (a record at
    0.034 s), sliding under it with µ = 0.4."""
    space = design_space(load_scene(ROOT / "problems" / "hold_time_planar.yaml"))
    setup = replace(space.baseline, duration=0.04, finger_model="spatial")
    return setup, simulate_grasp(setup, LOOP_SIMULATOR, SPATIAL_NODES)


def stage_inputs(setup, record, i: int) -> dict:
    """The finger function's inputs for finger i at a simulator record."""
    v, gf = parameters_of(setup), setup.grasper.fingers[i]
    key = f"fingers.{gf.design_name}."
    fp = [v[key + "angle"] + gf.phase, v[key + "height"], gf.mount.radius, v[key + "phi_x"],
          v[key + "phi_y"], v[key + "length"]]
    return {"state": record.y, "t": record.t, "fp": fp, "g": [v["spacing"], v["drum_speed"]],
            "k": 1.0, "belt": record.belt_speed, "z0": record.fingers[i].solution.extras["z"]}


@pytest.fixture(scope="module")
def finger_4a(placed):
    """Finger 4a's NLP function, interpreted (the formula, not the compiler:
    compiling it takes 30-60 s on an empty cache) and built here for the
    record's contact mode (a function is built when first asked for), with
    its inputs and the simulator's state at the last record."""
    from design.solvers.optimize.finger_load import FingerLoad
    setup, run = placed
    i = [gf.name for gf in setup.grasper.fingers].index("4a")
    record = run.trajectory.records[-1]
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("DESIGN_COMPILE", "0")
        load = FingerLoad(setup.grasper.fingers[i], setup.grasper, setup.bird,
                          setup.finger_friction, SPATIAL_NODES, 4, "spatial")
        load.function(record.fingers[i].solution.extras["mode"])
    return load, stage_inputs(setup, record, i), record.fingers[i], record


def test_the_nlp_finger_is_the_simulators(finger_4a):
    """From the simulator's state and contact unknowns, the NLP's finger
    solves the same contact (z unchanged to 1e-9 of its scale) and gives the
    simulator's force magnitude and its load on the bird from both drums
    (the mirror finger: X and Z the same, Y mirrored) to 1e-9 relative: the
    friction law is the same forward difference of the same frames."""
    load, inputs, state, _ = finger_4a
    mode = state.solution.extras["mode"]
    out, force, z = load.function(mode)(*(inputs[n] for n in load.inputs))
    z_sim = inputs["z0"]
    assert np.abs(np.asarray(z).ravel() - z_sim).max() <= 1e-9 * np.abs(z_sim).max()
    assert state.magnitude > 5.0
    assert float(force) == pytest.approx(state.magnitude, rel=1e-9)
    f, r = state.force, state.point - np.array([inputs["state"][0], 0.0, inputs["state"][1]])
    expected = 2 * np.array([f[0], f[2], r[2] * f[0] - r[0] * f[2]])
    assert np.allclose(np.asarray(out).ravel(), expected, rtol=1e-9, atol=1e-9 * abs(f).max())


def test_the_spatial_jacobian_is_the_rootfinders_derivative(finger_4a, monkeypatch):
    """The explicit Jacobian (the adjoint of the contact, dense LU) against
    CasADi's derivative through the rootfinder, in every differentiable
    input: the state (its rates move the friction), t, the finger's design,
    the drums and the stiffness scale; to 1e-9 of its largest entry, as the
    planar finger's (tests/test_compiled.py; measured 4.8e-13: both solve the
    same contact to its Newton tolerance)."""
    monkeypatch.setenv("DESIGN_COMPILE", "0")     # CasADi's derivative needs the SX
    from design.solvers.optimize.finger_load import SpatialStage, StageFunctions
    load, inputs, state, _ = finger_4a
    mode = state.solution.extras["mode"]
    F = load.function(mode)
    sizes = SpatialStage.sizes
    st = StageFunctions(load.transcriptions[mode], load.constants.size, SpatialStage)
    x = ca.MX.sym("x", sum(sizes.values()))
    z0 = ca.MX.sym("z0", load.n_z[mode])
    c = ca.DM(load.constants)
    root = st.tr.rootfinder(1e-12, 30, True)(z0, st.pre(x, c))
    out = ca.vertcat(*st.loads(x, root, c))
    reference = ca.Function("reference", [x, z0], [ca.jacobian(out, x)])
    x0 = ca.vertcat(*[ca.DM(inputs[n]) for n in sizes])
    ref = np.asarray(ca.densify(reference(x0, inputs["z0"])))
    values = F(*(inputs[n] for n in load.inputs))
    blocks = F.jacobian()(*(inputs[n] for n in load.inputs), *values)
    n_in = len(load.inputs)
    ours = np.asarray(ca.densify(ca.vertcat(*[ca.horzcat(*blocks[o * n_in:o * n_in + len(sizes)])
                                              for o in (0, 1)])))
    scale = np.abs(ref).max()
    assert scale > 0 and np.abs(ours - ref).max() <= 1e-9 * scale
    # the rates matter: the friction follows the sliding
    rates = slice(3, 6)
    assert np.abs(ref[:, rates]).max() > 1e-3 * scale


def test_the_nlp_calls_the_spatial_finger_with_each_nodes_state(monkeypatch):
    """At the simulation's own states, every first RK stage's finger force
    in the NLP (the cap's rows) is the finger function's at that node's
    whole state, time and the baseline design, to the last bit: the NLP
    passes the rates the friction needs, not the pose alone."""
    monkeypatch.setenv("DESIGN_COMPILE", "0")
    space = placed_space(0.5)
    run = prefetch.result(PLACED_HOLD, placed_hold)
    schedule = schedule_of(run, 0.005)
    nlp = DesignNLP(space, schedule, run, 1e3, NLPSettings(beam_intervals=SPATIAL_NODES))
    forces = np.asarray(nlp.functions(nlp.x0)[2]).ravel()
    v, grasper = parameters_of(space.baseline), space.baseline.grasper
    checked, n, t_phase = 0, 0, schedule.t_start
    for phase in schedule.phases:
        h = phase.duration / phase.intervals
        for k in range(phase.intervals):
            for s, contacts in enumerate(phase.contacts[k]):
                for i, contact in enumerate(contacts):
                    if contact is None:
                        continue
                    if STAGES[s] == 0.0 and s == 0:
                        load = nlp.fingers[i]
                        gf = grasper.fingers[i]
                        key = f"fingers.{gf.design_name}."
                        fp = [v[key + "angle"] + gf.phase, v[key + "height"], gf.mount.radius,
                              v[key + "phi_x"], v[key + "phi_y"], v[key + "length"]]
                        inputs = {"state": phase.states[k], "t": t_phase + k * h, "fp": fp,
                                  "g": [v["spacing"], v["drum_speed"]], "k": 1.0,
                                  "belt": nlp.setup.conveyor.speed, "z0": contact.z}
                        _, force, _ = load.function(contact.mode)(
                            *(inputs[name] for name in load.inputs))
                        assert forces[n] == pytest.approx(float(force), rel=1e-12, abs=1e-12)
                        checked += 1
                    n += 1
        t_phase += phase.duration
    assert n == forces.size and checked > 50
    assert forces.max() > 20.0                   # finger 4a holds the bird: real contacts


def on_the_belt():
    """The placed bird's spatial run to 0.245 s at the design loop's
    tolerance (3 s CPU), with its setup: finger 5a's tip is on the belt."""
    space = placed_space(0.245)
    setup = space.setup(space.scale(space.base_values))
    return setup, simulate_grasp(setup, LOOP_SIMULATOR, SPATIAL_NODES)


@pytest.fixture(scope="module")
def finger_5a_on_the_belt():
    """Finger 5a pressing the placed mean bird while its tip rests on the belt
    (the spatial run to 0.245 s, 3 s CPU: its last record has 5a in mode
    interior+belt at about 17 N), with its NLP function, interpreted."""
    from design.solvers.optimize.finger_load import FingerLoad
    setup, run = prefetch.result(ON_THE_BELT, on_the_belt)
    i = [gf.name for gf in setup.grasper.fingers].index("5a")
    record = run.trajectory.records[-1]
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("DESIGN_COMPILE", "0")
        load = FingerLoad(setup.grasper.fingers[i], setup.grasper, setup.bird,
                          setup.finger_friction, SPATIAL_NODES, 4, "spatial",
                          setup.finger_belt_friction)
    return load, stage_inputs(setup, record, i), record.fingers[i], record


def test_the_nlp_finger_on_the_belt_is_the_simulators(finger_5a_on_the_belt):
    """The same as for finger 4a, with finger 5a's tip on the belt: the NLP's
    two-segment contact, the belt's plane and its friction law from the
    finger's frames and the belt's speed, give the simulator's contact and
    force to 1e-9 relative."""
    load, inputs, state, _ = finger_5a_on_the_belt
    mode = state.solution.extras["mode"]
    assert mode == "interior+belt" and state.magnitude > 10.0 and state.belt_force > 0.5
    out, force, z = load.function(mode)(*(inputs[n] for n in load.inputs))
    z_sim = inputs["z0"]
    assert np.abs(np.asarray(z).ravel() - z_sim).max() <= 1e-9 * np.abs(z_sim).max()
    assert float(force) == pytest.approx(state.magnitude, rel=1e-9)
    f, r = state.force, state.point - np.array([inputs["state"][0], 0.0, inputs["state"][1]])
    expected = 2 * np.array([f[0], f[2], r[2] * f[0] - r[0] * f[2]])
    assert np.allclose(np.asarray(out).ravel(), expected, rtol=1e-9, atol=1e-9 * abs(f).max())


def test_a_run_stops_where_its_belt_contact_costs_more_than_its_budget(monkeypatch):
    """The count of the belt continuations' Newton solves is the run's own
    (the same on every machine): a budget below it stops the run, not ok,
    saying where and why, as soon as the count passes it (at the evaluation
    that passes it, an accepted instant's as a trial's); the unlimited run
    goes to its end."""
    setup, run = prefetch.result(ON_THE_BELT, on_the_belt)
    assert run.summary["ok"]
    stopped = simulate_grasp(setup, replace(LOOP_SIMULATOR, max_newton_solves=1e-6),
                             SPATIAL_NODES)
    assert not stopped.summary["ok"]
    assert re.search(r"Newton's method \d+ times, over the budget of 1e-06 per simulated "
                     r"second", stopped.summary["message"])
    assert stopped.trajectory.records[-1].t < run.trajectory.records[-1].t
    # a budget of 2 calls in the run (it makes 4) stops it at the evaluation
    # that makes the third, not at the next accepted instant: at the end of
    # a step that a finger's first touch inside it then shortens, not one of
    # the instants the whole run accepts
    evaluations = []
    evaluate = FingerForces.evaluate

    def counted(self, t, y, commit=False):
        try:
            return evaluate(self, t, y, commit)
        finally:
            evaluations.append((t, commit, self.newton_solves))
    monkeypatch.setattr(FingerForces, "evaluate", counted)
    simulate_grasp(setup, LOOP_SIMULATOR, SPATIAL_NODES)          # the whole run's evaluations
    two = simulate_grasp(setup, replace(LOOP_SIMULATOR, max_newton_solves=2 / setup.duration),
                         SPATIAL_NODES)
    found = re.search(r"stopped at t = ([\d.]+) s: .* method (\d+) times",
                      two.summary["message"])
    assert not two.summary["ok"] and int(found.group(2)) == 3
    # the third call is an accepted instant's, and the next trial is elsewhere
    t_passed, at_commit, _ = next(e for e in evaluations if e[2] > 2)
    next_trial = next(t for t, commit, n in evaluations if n > 2 and not commit)
    assert at_commit and found.group(1) == f"{t_passed:.4f}" != f"{next_trial:.4f}"
    accepted = np.array([r.t for r in run.trajectory.records])
    assert 0.0 < float(found.group(1)) < run.trajectory.records[-1].t
    assert np.min(np.abs(accepted - float(found.group(1)))) > 5e-5


def test_every_contact_starts_at_an_instant_where_its_finger_first_touches_the_bird():
    """No contact starts inside an integrator step: each finger that touches
    the bird at an accepted instant and did not at the one before starts at
    a located first touch (an event), and a bird-only contact starts there
    without force to speak of: 1-2 nm deep at the fingers' 100-1000 N/m,
    under 1e-5 N (measured at most 1.8e-6 N). (A finger on the belt whose
    first touch would pull grazes the bird until 20 µm inside:
    design/solvers/contact/belt_continuation.py's GRAZE_DEPTH.) The placed
    bird's run to 0.245 s: fingers 1a, 2a, 4a and 5a touch it."""
    setup, run = prefetch.result(ON_THE_BELT, on_the_belt)
    records = run.trajectory.records
    touches = {t for t, name in run.trajectory.events if name == "a finger touches the bird"}
    starts = [(now.t, state) for before, now in zip(records, records[1:])
              for was, state in zip(before.fingers, now.fingers)
              if not SpatialFinger.touching(was.continued)
              and SpatialFinger.touching(state.continued)]
    assert len(starts) >= 5
    for t, state in starts:
        assert t in touches
        if isinstance(state.continued, SpatialState):
            assert state.magnitude < 1e-5
