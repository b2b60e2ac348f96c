"""The thesis's grasp simulations (chapter V) set up from the shipped models."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from scipy.optimize import brentq

from design.io.files import TOOLKIT_ROOT
from design.io.fingers import read_finger
from design.io.grasp_scene import GraspSettings, read_bird, read_conveyor, read_grasper
from design.io.reader import Reader
from design.physics.bird import Conveyor, Legs, belt_motion
from design.physics.belt import Belt
from design.solvers.grasp.simulation import SPATIAL_NODES, GraspSetup

MODELS = TOOLKIT_ROOT / "models"
OMEGA = 20 * 2 * np.pi / 60
#: Table 5-3 (mean bird), 5-4 (football) and 5-5 (bird sizes) starts, m
MEAN_START, FOOTBALL_START, SIZES_START = -0.075, -0.305, -0.381
#: the finger model the chapter V comparisons use: the bird's surface normal
#: at the contacts lies up to 0.8-0.97 along the fingers' stiff axes, beyond
#: the planar model's limit (design/solvers/grasp/validity.py)
VALIDATION_MODEL = "spatial"
#: Table 5-3's 0.6 s from X0 (Figures 5-5 to 5-9: -0.075 to +0.15 m); the
#: football's one and a half drum cycles of video (§5.3)
MEAN_DURATION, FOOTBALL_DURATION = 0.6, 1.6


def load_model(kind_reader, *path):
    """A shipped model (finger, grasper, bird, conveyor) from models/<path>."""
    r = Reader("models")
    model = kind_reader(r, str(MODELS.joinpath(*path)), "", MODELS)
    r.raise_if_any()
    return model


def with_lower(grasper, finger_file: str, groups: tuple[str, ...] = ("lower",)):
    """The grasper with every finger of ``groups`` in another finger model."""
    model = load_model(read_finger, "fingers", finger_file)
    return grasper.with_models({g: model for g in groups})


def with_phi_x(setup: GraspSetup, family: str, degrees: float) -> GraspSetup:
    """The setup with every set's copy of finger ``family`` at φx = ``degrees``
    (Table 5-1's sense, as the grasper file uses it)."""
    return replace(setup, grasper=setup.grasper.remounted({family: {"phi_x": np.radians(degrees)}}))


def advanced(grasper, t_skip: float, omega: float = OMEGA):
    """The grasper's fingers where they are t_skip seconds later."""
    return replace(grasper, fingers=tuple(
        replace(f, mount=replace(f.mount, angle=f.mount.angle - omega * t_skip))
        for f in grasper.fingers))


def belt_arrival(conveyor: Conveyor, x0: float, x1: float) -> float:
    """Time (s) the belt takes to carry a bird riding it from x0 to x1 (m),
    slowing where its centre passes the conveyor's start position."""
    if not conveyor.decelerates or conveyor.start_position is None \
            or x1 <= conveyor.start_position:
        return (x1 - x0) / conveyor.speed
    start = max(conveyor.start_position - x0, 0.0) / conveyor.speed
    args = (conveyor.speed, conveyor.final_speed, conveyor.rate, start)
    return brentq(lambda t: belt_motion(t, *args)[2] - (x1 - x0), 0.0,
                  (x1 - x0) / conveyor.final_speed + 1.0, xtol=1e-12)


def designed_phase(setup: GraspSetup, start: float | None = None) -> GraspSetup:
    """The setup with the drums turned back so that a bird riding the belt
    from ``start`` (m; default the setup's own start) reaches Table 5-3's
    X0 = -0.075 m just as every finger reaches its Table 5-1 angle: the phase
    of the thesis's mean-bird run, the grasper's timing as designed. The
    thesis prints no drum phase for starts further upstream (Tables 5-4,
    5-5); read literally (Table 5-1's angles at their own t = 0) the bird
    arrives between two finger sets."""
    x0 = setup.start_x if start is None else start
    t1 = belt_arrival(setup.conveyor, x0, MEAN_START)
    return replace(setup, grasper=advanced(setup.grasper, -t1, setup.drum_speed))


def turned(setup: GraspSetup, degrees: float) -> GraspSetup:
    """The setup with the drums turned on by ``degrees`` (every finger that
    much further along its sweep at t = 0)."""
    return replace(setup, grasper=advanced(setup.grasper, np.radians(degrees) / setup.drum_speed,
                                           setup.drum_speed))


def slotted(setup: GraspSetup) -> GraspSetup:
    """The setup on a slotted pallet: every set's finger 5 passes through
    slots cut for it (the thesis prints no pallet; the default belt is solid)."""
    return replace(setup, belt=Belt(slots=frozenset({"5"})))


def thesis_setup(t_skip: float = 0.0, duration: float = 2.0, lower: str = "hard",
                 bird_file: str = "mean_1_80kg.yaml", start: float = MEAN_START,
                 conveyor_file: str = "constant_0457.yaml", friction: float = 0.4,
                 legs: Legs = Legs(), finger_model: str = "planar") -> GraspSetup:
    """A bird through the Table 5-1 grasper (hard or soft lower fingers),
    started ``t_skip`` seconds in: fingers advanced by ω t_skip and the bird by
    v t_skip, so that a short run covers the grasp itself (valid while nothing
    touches before t_skip)."""
    grasper = load_model(read_grasper, "graspers", "thesis_table_5_1.yaml")
    if lower == "soft":
        grasper = with_lower(grasper, "thesis_nonuniform_soft.yaml")
    bird = load_model(read_bird, "birds", bird_file)
    conveyor = load_model(read_conveyor, "conveyors", conveyor_file)
    return GraspSetup(advanced(grasper, t_skip), bird, conveyor, OMEGA,
                      start + conveyor.speed * t_skip, friction, friction, legs, duration,
                      finger_model)


def set_period(grasper, omega: float = OMEGA) -> float:
    """Time (s) after which the next finger set stands where the last one
    stood: 2 π / (sets ω), 1 s for Table 5-1's three sets at 20 rpm."""
    return 2 * np.pi / (grasper.sets * omega)


def mean_bird_setup(lower: str = "soft", model: str = VALIDATION_MODEL,
                    arriving: bool = True) -> GraspSetup:
    """Table 5-3's mean bird on the constant belt, µ = 0.4; lower fingers
    ``hard``, ``soft`` or ``constant`` (every finger EI = 0.08 N m²).

    The bird arrives: it starts one set period (1 s) upstream of Table 5-3's
    X0 = -0.075 m and reaches -0.075 m as the next set stands at Table 5-1's
    angles, the thesis's phase, having ridden into the fingers. Placed at
    -0.075 m at t = 0 it would start inside finger 4a's reach, held off the
    belt (N = 0) by a finger that never swept into it (15.7 N at t = 0 with
    soft lower fingers); ``arriving=False`` runs that start as printed."""
    s = thesis_setup(0.0, MEAN_DURATION, "hard" if lower == "constant" else lower,
                     finger_model=model)
    if arriving:
        lead = set_period(s.grasper, s.drum_speed)
        s = replace(s, start_x=s.start_x - s.conveyor.speed * lead, duration=s.duration + lead)
    if lower == "constant":
        s = replace(s, grasper=with_lower(s.grasper, "thesis_uniform.yaml", ("upper", "lower")))
    return s


def football_setup(start: float = FOOTBALL_START, friction: float = 1.16,
                   phi_x3: float = 60.0, model: str = VALIDATION_MODEL,
                   upper_tilt: float | None = None, phase: float = 0.0) -> GraspSetup:
    """The Table 5-4 football on the Figure 5-10 belt from ``start`` (m): the
    Table 5-1 grasper with finger 3 at φx = ``phi_x3`` (Figures 5-16 to 5-18
    use 60°) and fingers 1 and 2 at φy = ``upper_tilt`` (deg; None: Table
    5-1's -15°), no legs. The drums keep one timing whatever the start,
    :func:`designed_phase` for Table 5-4's X0 = -0.305 m, turned on by
    ``phase`` (deg)."""
    s = thesis_setup(0.0, FOOTBALL_DURATION, "hard", "football.yaml", start,
                     "decelerate_figure_5_10.yaml", friction, Legs(0.0, 0.0), model)
    s = with_phi_x(replace(s, conveyor_friction=1.16), "3", phi_x3)
    if upper_tilt is not None:
        tilt = np.radians(upper_tilt)
        s = replace(s, grasper=s.grasper.remounted({n: {"phi_y": tilt} for n in ("1", "2")}))
    return turned(designed_phase(s, FOOTBALL_START), phase)


def sizes_setup(bird: str) -> GraspSetup:
    """A Table 5-5 bird from X0 = -0.381 m, µ = 0.4, on the Figure 5-10 belt
    (the football studies' profiles; Figure 5-19's X axis starts at -0.25 m),
    the Table 5-1 grasper in the football's drum timing (:func:`football_setup`):
    §5.4 runs the football's studies with another bird."""
    s = thesis_setup(0.0, FOOTBALL_DURATION, "hard", f"{bird}.yaml", SIZES_START,
                     "decelerate_figure_5_10.yaml", 0.4, Legs(), VALIDATION_MODEL)
    return designed_phase(s, FOOTBALL_START)


def simulate_all(setups: dict[str, GraspSetup], progress=None,
                 budget: float | None = None) -> dict:
    """Each setup simulated (GraspRun each, by name), each within ``budget`` s
    of wall time if given; ``progress(message)`` is called before each run."""
    from design.solvers.grasp.integrate import IntegratorSettings
    from design.solvers.grasp.simulation import simulate_grasp

    runs = {}
    for k, (name, setup) in enumerate(setups.items(), 1):
        if progress:
            progress(f"grasp run {k}/{len(setups)}: {name}")
        runs[name] = simulate_grasp(setup, IntegratorSettings(max_wall_time=budget),
                                    contact_nodes(setup))
    return runs


def contact_nodes(setup: GraspSetup) -> int:
    """Collocation intervals per contact the chapter V runs use: the spatial
    rod's 3 (within 5e-6 of 10, benchmarks/spatial_mesh.py), else a grasp
    scene's default."""
    return SPATIAL_NODES if setup.finger_model == "spatial" else GraspSettings().contact_nodes
