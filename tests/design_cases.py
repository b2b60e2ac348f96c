"""A short grasp for the optimiser's tests: the mean bird through a test
grasper (tests/data/one_set_grasper.yaml: one set of Table 5-1's fingers at
angles read under the superseded convention, whose hold varies smoothly with
the design) on a constant belt from X0 = -0.457 m, started 0.6 s in (fingers
and bird advanced so that nothing touches before), 0.85 s long; the hold is
0.36-0.67 s.

Its simulations are most of the test suite's time (5-15 s each), and
several tests need the very same run, some through ``design simulate`` or
``design solve``; :func:`sharing_simulations` computes each distinct one
once per session, and those known before the first test starts
(:func:`prefetch_jobs`) are computed ahead on the machine's other core
(tests/prefetch.py)."""

from __future__ import annotations

import contextlib
import copy
import dataclasses
import functools
import itertools
import json
from dataclasses import replace

from pathlib import Path

import numpy as np
import pytest

from design.io.grasp_scene import GraspSettings, read_grasper
from design.io.scene_writer import grasp_spec
from design.reproduce.grasp import advanced, load_model, thesis_setup
from design.solvers.grasp import simulation
from design.solvers.grasp.integrate import IntegratorSettings
from design.solvers.optimize.policy import loop_settings
from design.solvers.optimize.trust_region import LOOP_SIMULATOR
from design.solvers.optimize.variables import DesignSpace, Variable, timed_conveyor
from tests import prefetch

GRASPER = Path(__file__).parent / "data" / "one_set_grasper.yaml"

#: the short grasp's scene settings: 6 contact nodes, integrated as the design
#: loop does (LOOP_SIMULATOR)
SCENE = GraspSettings(LOOP_SIMULATOR, 6)
#: the optimiser tests' loop settings: those of a short problem file on a
#: 10 ms grid, as the solve layer's policy makes them, so that a test calling
#: the loop's functions and a ``design solve`` of such a file ask for the
#: same simulations (and verifications) of the short grasp and share them
LOOP = loop_settings({"time_step": 0.01, "max_iter": 150}, SCENE)


def short_setup():
    s = thesis_setup(t_skip=0.6, duration=0.85, start=-0.457)
    grasper = advanced(load_model(read_grasper, str(GRASPER)), 0.6)
    return replace(s, grasper=grasper, conveyor=timed_conveyor(s.conveyor, None))


def stiffness_space(*groups: str, lo: float = 0.5, hi: float = 1.5) -> DesignSpace:
    """Group stiffness scales as the variables (baseline 1)."""
    return DesignSpace(short_setup(), [Variable(f"groups.{g}.stiffness_scale", lo, hi, 1.0)
                                       for g in groups])


def short_problem_file(path: Path, variables: dict, model_check: str = "none",
                       **solver) -> Path:
    """Write a design problem on the short grasp (cap: the baseline's peak,
    10 ms grid) to ``path`` (JSON is YAML); ``solver``: further settings.
    No spatial model check unless asked for (12 s CPU of background runs;
    tests/test_reports.py's design run has it)."""
    scene = grasp_spec(short_setup(), SCENE, "short", "")
    path.write_text(json.dumps({"kind": "design", "scene": scene, "cap": "baseline",
                                "variables": variables, "model_check": model_check,
                                "solver": {"time_step": 0.01, **solver}}))
    return path


#: every distinct simulation of the session (see :func:`sharing_simulations`)
_RUNS: dict[str, simulation.GraspRun] = {}


#: labels that no equation reads; a setup read back from a scene file has none
_LABELS = {("Grasper", "name"), ("Finger", "name")}
_unique = itertools.count()


def _canonical(value):
    """``value`` as nested tuples of numbers and strings, equal exactly when
    the simulation's inputs are (unlike a pickle, which also records which
    parts are one shared object); labels left out (see ``_LABELS``)."""
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        kind = type(value).__name__
        return (kind, tuple((f.name, _canonical(getattr(value, f.name)))
                            for f in dataclasses.fields(value) if (kind, f.name) not in _LABELS))
    if isinstance(value, (list, tuple)):
        return tuple(_canonical(v) for v in value)
    if isinstance(value, dict):
        return tuple(sorted((repr(k), _canonical(v)) for k, v in value.items()))
    if isinstance(value, (set, frozenset)):
        return ("set", tuple(sorted(_canonical(v) for v in value)))
    if isinstance(value, np.ndarray):
        return ("ndarray", value.dtype.str, value.shape, tuple(value.ravel().tolist()))
    if value is None or isinstance(value, (bool, int, float, str, np.number)):
        return (type(value).__name__, repr(value))
    return ("never shared", next(_unique))          # unknown: computed every time


def _inputs(setup, integrator, contact_nodes, reach_filter) -> str:
    """A simulation's inputs as one string (floats by repr, exact)."""
    return repr(_canonical((setup, integrator, contact_nodes, reach_filter)))


def shared_simulate_grasp(setup, integrator: IntegratorSettings = IntegratorSettings(),
                          contact_nodes: int = 6, reach_filter: bool = True, progress=None,
                          watch=None):
    """:func:`~design.solvers.grasp.simulation.simulate_grasp`, run once per
    distinct input in the session; the run returned carries the caller's
    setup. Without a wall-time limit the simulation is deterministic, so a
    repeat would give the same run; its records are shared, so a test must
    not change them. A run that a watch may end is not shared."""
    if integrator.max_wall_time is not None or watch is not None:   # not the inputs alone
        return simulation.simulate_grasp(setup, integrator, contact_nodes, reach_filter, progress,
                                         watch)
    key = _inputs(setup, integrator, contact_nodes, reach_filter)
    if key not in _RUNS:
        # computed ahead by the prefetch worker if it was given these inputs
        _RUNS[key] = prefetch.result(key, _simulate, setup, integrator, contact_nodes,
                                     reach_filter, progress)
    return replace(_RUNS[key], setup=setup)


def _simulate(setup, integrator, contact_nodes, reach_filter, progress=None):
    return simulation.simulate_grasp(setup, integrator, contact_nodes, reach_filter, progress)


#: the prefetch worker's first job: see :func:`compile_finger_loads`
COMPILE = "tests/design_cases.py: the design NLP's compiled finger functions"


def compile_finger_loads() -> int:
    """Build the short grasp's finger functions for the design NLP (6
    intervals, degree 4, both contact modes), which compiles them into the
    cache (design/solvers/compiled.py) if they are not there: about 7 s of gcc
    on an empty cache that the optimiser tests would otherwise wait for.
    Returns how many fingers were built."""
    from design.solvers.optimize.finger_load import FingerLoad
    setup = short_setup()
    for gf in setup.grasper.fingers:
        FingerLoad(gf, setup.grasper, setup.bird, setup.finger_friction, 6, 4)
    return len(setup.grasper.fingers)


def prefetched_simulation(setup, integrator, contact_nodes, reach_filter):
    """The prefetch worker's job: the run, also kept in the worker's own
    cache, where its later jobs (the short design solve) find it."""
    return shared_simulate_grasp(setup, integrator, contact_nodes, reach_filter)


class _Asked(Exception):
    pass


def asked(call) -> tuple:
    """The inputs (setup, integrator, contact nodes, reach filter) of the first
    simulation that ``call()`` asks the design loop's simulator for; nothing
    is simulated. So the prefetched inputs are the tests' own, settings such
    as the verification's resolution included."""
    def stop(setup, integrator=IntegratorSettings(), contact_nodes=6, reach_filter=True,
             progress=None, watch=None):
        raise _Asked(setup, integrator, contact_nodes, reach_filter)
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr("design.solvers.optimize.trust_region.simulate_grasp", stop)
        try:
            call()
        except _Asked as found:
            return found.args
    raise RuntimeError("no simulation asked for")


def prefetch_jobs() -> list[tuple[str, tuple, list[str]]]:
    """The shared simulations the default run needs, as (key, inputs, the
    tests that ask for them): the short grasp's baseline at the loop's
    tolerance (:data:`LOOP`), its baseline and stiff lower fingers (scale 2)
    at the verification's 4x finer resolution, the stiff design at the
    loop's, and the baseline at the scenes' default tolerance."""
    from design.solvers.optimize.trust_region import simulate, verify
    settings = LOOP
    space = stiffness_space("lower", hi=2.0)
    base = space.scale(space.base_values)
    design = ["tests/test_design_solve.py::test_verification_catches_a_design_over_the_cap",
              "tests/test_design_solve.py::test_a_failed_verification_exits_1_and_says_so"]
    design_report = ["tests/test_reports.py::test_design_report"]
    both = stiffness_space("lower", "upper")
    runs = [
        (asked(lambda: simulate(both, both.scale(both.base_values), settings)),
         ["tests/test_design_solve.py::test_kkt_conditions_hold_by_finite_differences",
          design[1], "tests/test_reports.py::test_grasp_report", *design_report,
          "tests/test_profile.py::"]),
        (asked(lambda: verify(space, base, settings)), [*design, *design_report]),
        (asked(lambda: verify(space, [1.0], settings)), design),
        (asked(lambda: simulate(space, [1.0], settings)), design[1:]),
        ((short_setup(), IntegratorSettings(), 6, True),
         ["tests/test_interrupt.py::test_ctrl_c_stops_design_solve_in_ipopt",
          "tests/test_run_status.py::"]),
    ]
    return [(_inputs(*inputs), inputs, users) for inputs, users in runs]


@contextlib.contextmanager
def sharing_simulations():
    """While open, the design loop (trust_region: its simulations and
    verifications) and ``design simulate`` of a grasp scene use
    :func:`shared_simulate_grasp`."""
    with pytest.MonkeyPatch.context() as patch:
        for module in ("design.solvers.optimize.trust_region", "design.run.grasp"):
            patch.setattr(f"{module}.simulate_grasp", shared_simulate_grasp)
        yield


def editable(scored):
    """A copy of a simulated design whose runs' summaries and attributes a
    test may change; the trajectories, which it does not, are shared (a
    deep copy of a run takes about a second)."""
    members = []
    for member in scored.members:
        run = copy.copy(member.run)
        run.summary = copy.deepcopy(member.run.summary)
        members.append(replace(member, run=run))
    return replace(scored, members=members)


#: the prefetch worker's key for :func:`single_bird_optimum` (tests/prefetch.py)
SINGLE_BIRD = "tests/design_cases.py: both stiffness scales' optimum under 18.5 N"


def single_bird_inputs():
    """(space, schedule, loop run, box) of the design NLP of both stiffness
    scales within 0.1 (scaled) of the baseline: with an 18.5 N cap, a box
    where it converges (in about 20 iterations)."""
    from design.solvers.optimize.schedule import schedule_of
    from design.solvers.optimize.trust_region import simulate
    space = stiffness_space("lower", "upper")
    d0 = space.scale(space.base_values)
    with sharing_simulations():
        run = simulate(space, d0, LOOP).run
    return space, schedule_of(run, 0.01), run, (np.clip(d0 - 0.1, 0, 1), np.clip(d0 + 0.1, 0, 1))


def single_bird_nlp():
    """:func:`single_bird_inputs`' NLP under an 18.5 N cap, the loop's settings."""
    from design.solvers.optimize.transcription import DesignNLP
    space, schedule, run, box = single_bird_inputs()
    return DesignNLP(space, schedule, run, 18.5, LOOP.nlp, box=box)


@functools.cache
def single_bird_optimum():
    """Ipopt's solution of :func:`single_bird_nlp` (6 s), once per process:
    the KKT test checks it, the population's twins compare with it."""
    return single_bird_nlp().solve()
