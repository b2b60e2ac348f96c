"""Design problems (``kind: design``): a baseline grasp, the variables with
bounds, the bruise cap, the design rules and the solver settings.

.. code-block:: yaml

    kind: design
    scene: grasp_mean_bird_hard.yaml            # a grasp scene file, or its content inline
    variables:                                  # name: [lower, upper]; the rest stay at baseline
      conveyor.start_time: [0.4 s, 1.2 s]
      conveyor.final_speed: [0.254 m/s, 0.457 m/s]
      groups.lower.stiffness_scale: [0.5, 2.0]
      fingers.4.angle: [-165 deg, -135 deg]
    cap: baseline              # N | baseline | {relative_to_baseline: 0.75} | a list: Pareto study
    rules: {sigma_lambda: 0.01, bird_spacing: 0.3}   # finger_sets: the grasper's sets
    population:                # optional: one design for several birds (robust design)
      objective: worst         # worst (the shortest hold) | mean (weighted by ``weight``)
      birds: [models/birds/small_1_20kg.yaml, {bird: models/birds/large_2_30kg.yaml, weight: 2}]
      screen: {starts: 4, max_simulations: 16}   # where the baseline breaks a bird's limits:
                               # the pattern search on the hardest bird alone from each start
                               # in turn, until one reaches its goal
                               # (design/solvers/optimize/feasibility.py); the defaults
    multistart: {starts: 8, seed: 0}   # optional: the loop from the baseline and 7 Sobol points
    model_check: spatial       # the default: baseline and optimum also run with the spatial
                               # finger (design/solvers/optimize/model_check.py); none: not
    robustness: true           # baseline and optimum also run in perturbed scenes (friction,
                               # drum phase, other birds, stiffness, a slotted pallet:
                               # design/solvers/optimize/robustness.py); default false
    solver: {time_step: 0.005, beam_intervals: 6, max_iter: 40, outer_iterations: 6,
             trust_region: 0.15, cap_margin: 0.25, ipopt: {}}   # beam_intervals: the
                               # finger mesh, by default the scene's contact_nodes;
                               # method: trust-region (default: Ipopt moves the design)
                               # or pattern (the simulator's lattice search, the same
                               # answer under round-off: pattern_search.py); pattern's
                               # max_simulations: designs evaluated (150), lattice:
                               # each box in this many units, the finest step (64;
                               # a power of two from 8 to 1024: a coarser lattice
                               # ends the search sooner, on a coarser point),
                               # survey: Sobol points of the box simulated first, the
                               # search starting from the best of them and the
                               # baseline (0; a power of two, counted in the budget)

Variable names: ``fingers.<name>.angle|phi_x|phi_y|length|height``,
``groups.<group>.stiffness_scale``, ``conveyor.speed|start_time|rate|final_speed``,
``drum_speed``, ``spacing``, ``bird_spacing`` (design/solvers/optimize/variables.py;
at most two of the line's drum_speed, conveyor.speed and bird_spacing, tied by
eq. 5.3, and only with ``solver: {method: pattern}``).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, replace
from pathlib import Path

from design.errors import ProblemFileError
from design.io.files import resolve
from design.io.grasp_scene import GraspScene, read_bird
from design.io.reader import Reader, did_you_mean, join
from design.physics.bird import Bird
from design.solvers.optimize.finger_load import STAGE_MODELS
from design.solvers.optimize.line import max_sets
from design.solvers.optimize.model_check import CHECK_MODEL
from design.solvers.optimize.policy import LOOP_METHODS, SOLVER_KEYS, loop_settings
from design.solvers.optimize.feasibility import SIMULATIONS, STARTS
from design.solvers.optimize.population import AGGREGATES
from design.solvers.optimize.transcription import Rules
from design.solvers.optimize.trust_region import LoopSettings
from design.solvers.optimize.variables import (CONVEYOR_FIELDS, FINGER_FIELDS, GLOBAL_FIELDS,
                                             GROUP_FIELDS, LINE)

#: a design problem's objectives: the longest hold, the highest line rate
OBJECTIVES = ("hold", "throughput")
#: starting designs of ``multistart: {}`` (the baseline and seven Sobol points)
DEFAULT_STARTS = 8

DIMENSIONS = {"angle": "angle", "phi_x": "angle", "phi_y": "angle", "length": "length",
              "height": "length", "stiffness_scale": "dimensionless", "start_time": "time",
              "rate": "acceleration", "final_speed": "speed", "speed": "speed",
              "drum_speed": "angular_speed", "spacing": "length", "bird_spacing": "length"}


@dataclass(frozen=True)
class Cap:
    """The bruise cap, one for every bird: ``value`` N, or ``relative`` × the
    design bird's (the scene's own) verified baseline peak."""

    value: float | None = None
    relative: float | None = None

    def resolve(self, baseline_peak: float) -> float:
        return self.value if self.value is not None else self.relative * baseline_peak

    def describe(self) -> str:
        if self.value is not None:
            return f"{self.value:g} N"
        return "the baseline's peak force" if self.relative == 1.0 else \
            f"{self.relative:g} x the baseline's peak force"


@dataclass(frozen=True)
class PopulationSpec:
    """The birds a robust design must hold, their weights (for ``mean``) and
    how their holds combine (design/solvers/optimize/population.py)."""

    birds: tuple[Bird, ...]
    weights: tuple[float, ...]
    objective: str = "worst"
    #: the feasibility screen (design/solvers/optimize/feasibility.py): its
    #: starts and each start's budget of simulations
    screen_starts: int = STARTS
    screen_simulations: int = SIMULATIONS


@dataclass(frozen=True)
class MultistartSpec:
    """How many starting designs (the baseline is one of them) and the Sobol
    sequence's seed; one start: the baseline alone, no multistart."""

    starts: int = 1
    seed: int = 0


@dataclass(frozen=True)
class DesignProblem:
    name: str
    scene: GraspScene
    variables: dict[str, tuple[float, float]]
    caps: list[Cap]
    rules: Rules
    #: the solver options as the problem states them (SI; any of
    #: design/solvers/optimize/policy.py's SOLVER_KEYS, the rest default)
    solver: dict
    description: str = ""
    #: several birds (robust design), or None: the scene's bird alone
    population: PopulationSpec | None = None
    #: the loop from several starting designs (design/solvers/optimize/multistart.py)
    multistart: MultistartSpec = MultistartSpec()
    #: the finger model baseline and optimum are also simulated with, or ``none``
    model_check: str = CHECK_MODEL
    #: baseline and optimum also simulated in the perturbed scenes of
    #: design/solvers/optimize/robustness.py
    robustness: bool = False
    #: ``hold`` (the longest hold) or ``throughput`` (the highest line rate
    #: with every bird held at least ``min_hold`` s: design/run/line.py)
    objective: str = "hold"
    min_hold: float = 0.0
    #: a throughput problem's numbers of finger sets, each a case (eq. 5.4)
    finger_sets: tuple[int, ...] = ()

    @property
    def pareto(self) -> bool:
        return len(self.caps) > 1

    @property
    def settings(self) -> LoopSettings:
        """The settings the design loop runs with: :attr:`solver` under the
        solve layer's policy (:func:`design.solvers.optimize.policy.loop_settings`),
        with the problem's objective."""
        return replace(loop_settings(self.solver, self.scene.settings),
                       objective=self.objective, min_hold=self.min_hold)


def variable_names(scene: GraspScene) -> list[str]:
    families = dict.fromkeys(gf.design_name for gf in scene.grasper.fingers)
    names = [f"fingers.{name}.{f}" for name in families for f in FINGER_FIELDS]
    names += [f"groups.{g}.{f}" for g in sorted({gf.group for gf in scene.grasper.fingers})
              for f in GROUP_FIELDS]
    return names + [f"conveyor.{f}" for f in CONVEYOR_FIELDS] + list(GLOBAL_FIELDS)


def read_design(reader: Reader, data: dict, base_dir: Path, name: str) -> DesignProblem | None:
    # a missing scene or variables key is already a problem (the top-level key check)
    scene = _scene(reader, data["scene"], base_dir) if "scene" in data else None
    variables = _variables(reader, data["variables"], scene) if "variables" in data else None
    caps = _caps(reader, data.get("cap", "baseline"))
    rules = _rules(reader, data.get("rules", {}))
    solver = _solver(reader, data.get("solver", {}))
    population = _population(reader, data["population"], base_dir) \
        if "population" in data else None
    multistart = _multistart(reader, data["multistart"]) if "multistart" in data \
        else MultistartSpec()
    line = [name for name in LINE if name in (variables or {})]
    if line and solver is not None and solver.get("method") != "pattern":
        reader.add("solver.method", f"{', '.join(line)} move the bird's arrival with the line "
                   "(eq. 5.3), which only the simulator follows: give method: pattern")
    if scene is not None and (line or data.get("objective") == "throughput"):
        period = 2 * math.pi / (scene.grasper.sets * scene.drum_speed)
        if scene.duration <= period:
            reader.add("scene.duration", f"{scene.duration:g} s: a line that moves needs the "
                       "bird arriving, one finger-set period upstream of where it meets its "
                       f"set (2 pi / (n omega) = {period:.3g} s), and a run that goes on after "
                       "it (design/solvers/optimize/variables.py)")
    if scene is not None and scene.finger_model not in STAGE_MODELS:
        reader.add("scene.finger_model", f"'{scene.finger_model}' is for simulations only: the "
                   f"design NLP models {' and '.join(STAGE_MODELS)} fingers")
    # the check runs the other finger model: none for a scene that is spatial already
    checks = (CHECK_MODEL, "none") if scene is None or scene.finger_model != CHECK_MODEL \
        else ("none",)
    model_check = reader.choice(data, "model_check", "", checks, default=checks[0])
    robustness = reader.boolean(data, "robustness", "", default=False)
    objective, min_hold, finger_sets = _line(reader, data, scene, solver, caps, multistart)
    if not reader.ok or None in (scene, variables, caps, rules, solver, multistart,
                                 model_check, robustness, objective) or \
            ("population" in data and population is None):
        return None
    return DesignProblem(name, scene, variables, caps, rules, solver,
                         data.get("description", ""), population, multistart, model_check,
                         robustness, objective, min_hold, finger_sets)


def _line(reader: Reader, data: dict, scene: GraspScene | None, solver: dict | None,
          caps: list | None, multistart: MultistartSpec | None) -> tuple:
    """``objective``, ``min_hold`` (s) and ``finger_sets`` (a throughput
    problem's; eq. 5.4 bounds the sets by the grasper's included angle)."""
    objective = reader.choice(data, "objective", "", OBJECTIVES, default="hold")
    line = {key: data[key] for key in ("min_hold", "finger_sets") if key in data}
    if objective != "throughput":
        for key in line:
            reader.add(key, "only a throughput problem has it (objective: throughput)")
        return objective, 0.0, ()
    duration = scene.duration if scene is not None else None
    min_hold = reader.quantity(data, "min_hold", "", "time", lo=0.0, lo_open=True,
                               hi=duration)
    if solver is not None and solver.get("method") != "pattern":
        reader.add("solver.method", "a throughput problem is solved by the pattern search: "
                   "give method: pattern")
    if caps is not None and len(caps) > 1:
        reader.add("cap", "a throughput problem takes one cap")
    if multistart is not None and multistart.starts > 1:
        reader.add("multistart", "a throughput problem starts from its baseline only")
    if solver is not None and solver.get("survey"):
        reader.add("solver.survey", "a throughput problem starts from its baseline only")
    sets: tuple[int, ...] = ()
    if "finger_sets" in data and scene is not None:
        top = max_sets(scene.grasper)
        given = data["finger_sets"] if isinstance(data["finger_sets"], list) \
            else [data["finger_sets"]]
        for i, n in enumerate(given):
            if isinstance(n, bool) or not isinstance(n, int) or not 1 <= n <= top:
                reader.add(join("finger_sets", i), f"expected an integer from 1 to {top} "
                           f"(eq. 5.4: 2 pi / the sets' included angle), got {n!r}")
        if not given:
            reader.add("finger_sets", f"an empty list (allowed: 1 to {top}, eq. 5.4)")
        elif len(set(map(str, given))) != len(given):
            reader.add("finger_sets", "a number of sets is repeated")
        sets = tuple(given)
    return objective, min_hold, sets


def _scene(reader: Reader, value: object, base_dir: Path) -> GraspScene | None:
    from design.io.scene import load_scene
    if isinstance(value, str):
        path = resolve(value, base_dir)
        if path is None:
            reader.add("scene", f"cannot find the grasp scene '{value}'")
            return None
        source: object = path
    elif isinstance(value, Mapping):
        source = {"kind": "grasp", **value}
    else:
        reader.add("scene", "expected a grasp scene file name or the scene's fields")
        return None
    try:
        scene = load_scene(source)
    except ProblemFileError as exc:
        for p in exc.problems:
            if isinstance(value, str):
                reader.record(p)
            else:
                reader.add(join("scene", p.field), p.message)
        return None
    if not isinstance(scene, GraspScene):
        reader.add("scene", "must be a grasp scene (kind: grasp)")
        return None
    return scene


def _variables(reader: Reader, value: object, scene: GraspScene | None):
    if not isinstance(value, Mapping):
        reader.add("variables", "expected a mapping of variable names to [lower, upper]")
        return None
    spec = dict(value)
    if not spec:
        reader.add("variables", "no design variable given")
        return None
    allowed = variable_names(scene) if scene is not None else None
    base = _baseline_values(scene) if scene is not None else {}
    out = {}
    for key, bounds in spec.items():
        path = join("variables", str(key))
        # without a scene (its own problem) only the name's last part can be checked
        dimension = DIMENSIONS.get(str(key).rsplit(".")[-1])
        if dimension is None or (allowed is not None and key not in allowed):
            reader.add(path, f"no such design variable (allowed: fingers.<name>.<"
                             f"{'|'.join(FINGER_FIELDS)}>, groups.<group>.stiffness_scale, "
                             f"conveyor.<{'|'.join(CONVEYOR_FIELDS)}>, "
                             f"{', '.join(GLOBAL_FIELDS)})"
                             f"{did_you_mean(key, allowed or list(DIMENSIONS))}")
            continue
        values = reader.quantities(spec, key, "variables", dimension)
        if values is None:
            continue
        if len(values) != 2:
            reader.add(path, "expected [lower, upper]")
        elif not values[0] < values[1]:
            reader.add(path, f"lower bound {values[0]:g} is not below upper bound {values[1]:g}")
        elif key.endswith(("stiffness_scale", "rate", "length", "drum_speed", "spacing",
                           "speed")) and values[0] <= 0:
            reader.add(path, f"lower bound {values[0]:g} must be > 0")
        elif key in base and not values[0] <= base[key] <= values[1]:
            reader.add(path, f"the bounds [{values[0]:g}, {values[1]:g}] do not contain the "
                             f"baseline's value {base[key]:g} (SI)")
        else:
            out[key] = (values[0], values[1])
    if all(name in spec for name in LINE):
        reader.add("variables", f"{', '.join(LINE)} are tied by eq. 5.3 (2 pi v = n dx "
                                "omega): at most two of them may be variables, the third "
                                "follows")
        return None
    return out


def _baseline_values(scene: GraspScene) -> dict[str, float]:
    """The scene's own value of every design variable (SI), except the belt's
    deceleration start, which a simulation decides."""
    from design.run.grasp import setup_of
    from design.solvers.optimize.variables import parameters_of, timed_conveyor
    setup = setup_of(scene)
    values = parameters_of(replace(setup, conveyor=timed_conveyor(setup.conveyor, 0.0)))
    values.pop("conveyor.start_time")
    return values


def _caps(reader: Reader, value: object) -> list[Cap] | None:
    items = value if isinstance(value, list) else [value]
    if not items:
        reader.add("cap", "an empty list")
        return None
    caps = []
    for i, item in enumerate(items):
        path = "cap" if not isinstance(value, list) else join("cap", i)
        if item == "baseline":
            caps.append(Cap(relative=1.0))
        elif isinstance(item, Mapping):
            spec = reader.mapping(item, path, required=("relative_to_baseline",))
            f = reader.quantity(spec or {}, "relative_to_baseline", path, "dimensionless",
                                lo=0.0, lo_open=True, hi=10.0) if spec is not None else None
            if f is not None:
                caps.append(Cap(relative=f))
        else:
            key, holder, field = (i, {i: item}, "cap") if isinstance(value, list) \
                else ("cap", {"cap": item}, "")
            v = reader.quantity(holder, key, field, "force", lo=0.0, lo_open=True)
            if v is not None:
                caps.append(Cap(value=v))
    return caps if len(caps) == len(items) else None


def _population(reader: Reader, value: object, base_dir: Path) -> PopulationSpec | None:
    spec = reader.mapping(value, "population", required=("birds",),
                          optional=("objective", "screen"))
    if spec is None:
        return None
    objective = reader.choice(spec, "objective", "population", AGGREGATES, default="worst")
    screen = reader.mapping(spec.get("screen", {}), "population.screen",
                            optional=("starts", "max_simulations"))
    starts = simulations = None
    if screen is not None:
        starts = reader.integer(screen, "starts", "population.screen", lo=1, hi=1024,
                                default=STARTS)
        simulations = reader.integer(screen, "max_simulations", "population.screen", lo=1,
                                     hi=10000, default=SIMULATIONS)
    items = spec["birds"]
    if not isinstance(items, list) or not items:
        reader.add("population.birds", "expected a non-empty list of birds (model files or "
                   "inline mappings, each optionally {bird: ..., weight: w})")
        return None
    birds, weights = [], []
    for i, item in enumerate(items):
        path = join("population.birds", i)
        weight: float | None = 1.0
        if isinstance(item, Mapping) and "bird" in item:
            entry = reader.mapping(item, path, required=("bird",), optional=("weight",))
            if entry is None:
                continue
            weight = reader.quantity(entry, "weight", path, "dimensionless", lo=0.0,
                                     lo_open=True, default=1.0)
            item, path = entry["bird"], join(path, "bird")
        bird = read_bird(reader, item, path, base_dir)
        if bird is not None and weight is not None:
            birds.append(bird)
            weights.append(weight)
    names = [b.name for b in birds]
    for name in {n for n in names if names.count(n) > 1}:
        reader.add("population.birds", f"the bird '{name}' is listed twice: each bird once, "
                   "with a weight for its share")
    if None in (objective, starts, simulations) or len(birds) != len(items):
        return None
    return PopulationSpec(tuple(birds), tuple(weights), objective, starts, simulations)


def _multistart(reader: Reader, value: object) -> MultistartSpec | None:
    spec = reader.mapping(value, "multistart", optional=("starts", "seed"))
    if spec is None:
        return None
    starts = reader.integer(spec, "starts", "multistart", lo=1, hi=1024,
                            default=DEFAULT_STARTS)
    seed = reader.integer(spec, "seed", "multistart", lo=0, hi=2 ** 31 - 1, default=0)
    return None if None in (starts, seed) else MultistartSpec(starts, seed)


def _rules(reader: Reader, value: object) -> Rules | None:
    spec = reader.mapping(value, "rules", optional=("sigma_lambda", "bird_spacing",
                                                    "finger_sets"))
    if spec is None:
        return None
    sigma = reader.quantity(spec, "sigma_lambda", "rules", "length", lo=0.0, default=0.0)
    spacing = reader.quantity(spec, "bird_spacing", "rules", "length", lo=0.0, lo_open=True,
                              default=None)
    sets = reader.integer(spec, "finger_sets", "rules", lo=1, hi=12, default=None) \
        if "finger_sets" in spec else None
    if sigma is None or ("finger_sets" in spec and sets is None):
        return None
    return Rules(sigma, spacing, sets)


#: a design problem's integer solver options: [lowest, highest]
SOLVER_INTEGERS = {"beam_intervals": (2, 32), "max_iter": (1, 10000), "outer_iterations": (0, 100),
                   "max_simulations": (1, 10000), "lattice": (8, 1024), "survey": (0, 1024)}
#: its other numeric solver options: dimension, lowest, highest, lowest excluded
SOLVER_QUANTITIES = {"time_step": ("time", 5e-4, 0.05, False),
                     "tolerance": ("dimensionless", 1e-12, 1e-2, False),
                     "trust_region": ("dimensionless", 0.0, 1.0, True),
                     "cap_margin": ("dimensionless", 0.0, 0.9, False)}


def _power_of_two(reader: Reader, key: str, value: int, allowed: str) -> bool:
    """Is solver option ``key``'s ``value`` a power of two? Where not, the
    problem says so, naming the ``allowed`` values."""
    if value & (value - 1):
        reader.add(join("solver", key), f"{value} is not a power of two ({allowed})")
        return False
    return True


def _survey(reader: Reader, stated: dict) -> int | None:
    """The pattern search's survey, ``stated["survey"]`` Sobol points: a power
    of two (the sequence's balanced prefixes), fewer than the search's budget,
    and only for the pattern search."""
    survey, budget = stated["survey"], stated.get("max_simulations",
                                                  LoopSettings.max_simulations)
    where = join("solver", "survey")
    if not _power_of_two(reader, "survey", survey, "1, 2, 4, ... 1024, or 0"):
        return None
    if stated.get("method", LoopSettings.method) != "pattern":
        reader.add(where, "a survey needs solver.method: pattern")
        return None
    if budget is not None and survey >= budget:
        reader.add(where, f"{survey} Sobol points leave nothing of the budget of {budget} "
                          "designs (solver.max_simulations)")
        return None
    return survey


def _solver(reader: Reader, value: object) -> dict | None:
    """The solver options the problem states, validated, in SI; the solve
    layer decides the rest (design/solvers/optimize/policy.py)."""
    spec = reader.mapping(value, "solver", optional=SOLVER_KEYS)
    if spec is None:
        return None
    stated = {key: reader.integer(spec, key, "solver", lo=lo, hi=hi)
              for key, (lo, hi) in SOLVER_INTEGERS.items() if key in spec}
    stated.update({key: reader.quantity(spec, key, "solver", dimension, lo=lo, hi=hi,
                                        lo_open=lo_open)
                   for key, (dimension, lo, hi, lo_open) in SOLVER_QUANTITIES.items()
                   if key in spec})
    if stated.get("lattice") and not _power_of_two(reader, "lattice", stated["lattice"],
                                                    "8, 16, 32, ... 1024"):
        stated["lattice"] = None
    if "method" in spec:
        stated["method"] = reader.choice(spec, "method", "solver", LOOP_METHODS)
    if stated.get("survey"):
        stated["survey"] = _survey(reader, stated)
    if "ipopt" in spec:
        if not isinstance(spec["ipopt"], Mapping):
            reader.add(join("solver", "ipopt"), "expected a mapping of Ipopt options")
            return None
        stated["ipopt"] = dict(spec["ipopt"])
    return None if None in stated.values() else stated
