"""The frames of a grasp run's animation, and what is drawn in them.

A run's result keeps the bird's state at evenly spaced frame times
(design/run/animation.py). At each frame every finger's contact is solved
at that state (:class:`~design.solvers.grasp.fingers.FingerForces`, committed
frame by frame in time order, each continued from the frame before), which
gives its deflected shape, its force on the bird and the contact point.

Conventions: world frame of docs/MODEL.md ("Frames"), SI units; the left
drum mirrors the right one (Y → -Y).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from design.physics.kinematics import MIRROR, Ellipsoid, rot_y
from design.report.grasp_figures import MM, drum_profile, finger_curves
from design.run.animation import STATE
from design.solvers.grasp.fingers import FingerForces
from design.solvers.grasp.simulation import GraspSetup

#: points kept of a deflected finger's shape (base and tip among them)
FINGER_POINTS = 12
#: arrow length per newton of a finger's force on the bird (mm/N)
ARROW_MM_PER_N = 5.0
#: the force colours, from no force (green) to the cap (red; above it too)
FORCE_SCALE = [[0.0, "#1a9850"], [0.5, "#fee08b"], [1.0, "#d73027"]]
BIRD_COLOUR = "#c8a064"
#: spacing of the stripes drawn across the belt, which travel with it (m)
STRIPE = 0.05


@dataclass
class Frame:
    """One instant of a run, right drum (SI, world frame): the bird's state
    (6,), N (N), the belt's travel (m), every finger's shape (3, n), force
    on the bird (3,) and contact point (3,) or None."""

    t: float
    y: np.ndarray
    normal: float
    belt_travel: float
    curves: list[np.ndarray]
    forces: np.ndarray
    points: list[np.ndarray | None]

    def touching(self, names: list[str]) -> list[str]:
        """The fingers pressing on the bird (right drum; the left mirrors them)."""
        return [n for n, f in zip(names, self.forces) if np.linalg.norm(f) > 0]


@dataclass
class RunFrames:
    """A run's frames with its setup; ``recorded`` the run's own recorded
    instants the frames were interpolated from."""

    label: str
    setup: GraspSetup
    frames: list[Frame]
    recorded: int

    @property
    def names(self) -> list[str]:
        return [gf.name for gf in self.setup.grasper.fingers]


def animated_runs(record: dict) -> list[RunFrames]:
    """The runs of a result's ``animation`` (design/run/animation.py), each
    set up from its scene and its fingers solved at every frame
    (:func:`solve_frames`). Raises
    :class:`~design.errors.ProblemFileError` for a scene that does not read,
    :class:`~design.solvers.grasp.fingers.ContactFailed` for a contact that
    cannot be solved."""
    from design.io.scene import load_scene
    from design.run.grasp import setup_of

    runs = []
    for label, run in record["runs"].items():
        scene = load_scene(run["scene"])
        runs.append(solve_frames(label, setup_of(scene), scene.settings.contact_nodes,
                                 run["states"], run["recorded_instants"]))
    return runs


def solve_frames(label: str, setup: GraspSetup, contact_nodes: int, states: dict,
                 recorded: int) -> RunFrames:
    """Every finger's contact solved at each frame's state (``states``: a
    :func:`~design.run.animation.frame_states` dict), in time order, each
    continued from the frame before. Raises
    :class:`~design.solvers.grasp.fingers.ContactFailed` where a contact
    cannot be solved."""
    forces = FingerForces(setup.grasper, setup.bird, setup.drum_speed, setup.finger_friction,
                          intervals=contact_nodes, model=setup.finger_model)
    y = np.column_stack([states[k] for k in STATE])
    frames = []
    for k, t in enumerate(states["t_s"]):
        _, fingers = forces.evaluate(t, y[k], commit=True)
        frames.append(Frame(t, y[k], states["N_N"][k], states["belt_travel_m"][k],
                            [_thinned(c) for c in finger_curves(setup, t, fingers)],
                            np.array([f.force for f in fingers]),
                            [f.point for f in fingers]))
    return RunFrames(label, setup, frames, recorded)


def _thinned(curve: np.ndarray) -> np.ndarray:
    """At most FINGER_POINTS of a finger's points, its ends kept."""
    n = curve.shape[1]
    return curve if n <= FINGER_POINTS else curve[:, np.linspace(0, n - 1, FINGER_POINTS).round()
                                                  .astype(int)]


def both_drums(curves: list[np.ndarray]) -> list[np.ndarray]:
    """The right drum's finger curves followed by their left mirror images."""
    return list(curves) + [MIRROR @ c for c in curves]


def arrows(frame: Frame) -> list[tuple[np.ndarray, np.ndarray, np.ndarray, float]]:
    """Both drums' force arrows: (tail, tip, force, magnitude) for every
    finger touching the bird and its mirror image; the tip at the contact
    point (m), the tail ARROW_MM_PER_N mm per N back along the force (N)."""
    out = []
    for f, p in zip(frame.forces, frame.points):
        magnitude = float(np.linalg.norm(f))
        if p is None or magnitude == 0.0:
            continue
        for m in (np.eye(3), MIRROR):
            tip, force = m @ p, m @ f
            out.append((tip - force * ARROW_MM_PER_N / MM, tip, force, magnitude))
    return out


def bird_surface(setup: GraspSetup, y: np.ndarray, n: int = 11) -> np.ndarray:
    """The bird's ellipsoid at state y as a grid of world points (3, n, 2n)."""
    b = setup.bird
    body = Ellipsoid(b.eta, b.lam, b.gamma, (y[0], 0.0, y[1]), y[2])
    polar, around = np.meshgrid(np.linspace(0.0, np.pi, n), np.linspace(0.0, 2 * np.pi, 2 * n),
                                indexing="ij")
    local = np.stack([b.eta * np.sin(polar) * np.cos(around),
                      b.lam * np.sin(polar) * np.sin(around), b.gamma * np.cos(polar)])
    return np.einsum("ij,jkl->ikl", body.rotation, local) + \
        np.asarray(body.center)[:, None, None]


def drum_surface(setup: GraspSetup, side: int, n: int = 36) -> np.ndarray:
    """The right (side = 1) or left (side = -1) drum's surface of revolution
    through :func:`drum_profile`, closed at both ends: world points
    (3, rings + 2, n)."""
    g = setup.grasper
    profile = drum_profile(setup)
    heights = [profile[0][0]] + [h for h, _ in profile] + [profile[-1][0]]
    radii = [0.0] + [r for _, r in profile] + [0.0]
    a = np.linspace(0.0, 2 * np.pi, n)
    local = np.stack([np.outer(radii, np.cos(a)), np.outer(radii, np.sin(a)),
                      np.outer(heights, np.ones(n))])
    origin = np.array([g.x, -g.spacing / 2, 0.0])
    world = np.einsum("ij,jkl->ikl", rot_y(g.tilt), local) + origin[:, None, None]
    return world if side == 1 else np.einsum("ij,jkl->ikl", MIRROR, world)


def belt_half_width(setup: GraspSetup) -> float:
    """Half the belt's drawn width (m): the gap between the drums (the
    scenes give no belt width)."""
    return setup.grasper.spacing / 2 - max(r for _, r in drum_profile(setup))


def stripes(run: RunFrames, travel: float, x_range: tuple[float, float]) -> list[np.ndarray]:
    """Stripes across the belt every STRIPE, moved on by the belt's travel (m)."""
    w = belt_half_width(run.setup)
    first = np.ceil((x_range[0] - travel) / STRIPE) * STRIPE + travel
    return [np.array([[x, x], [-w, w], [0.0005, 0.0005]])
            for x in np.arange(first, x_range[1], STRIPE)]


def extent(runs: list[RunFrames]) -> np.ndarray:
    """The box drawn (3, 2), in m: the drums, the fingers and the bird over
    every frame of the runs (the bird's centre widened by its largest
    semi-axis), and the belt."""
    pts = []
    for run in runs:
        b = run.setup.bird
        reach = max(b.eta, b.lam, b.gamma)
        centres = np.array([[f.y[0], 0.0, f.y[1]] for f in run.frames]).T
        pts += [drum_surface(run.setup, 1).reshape(3, -1), centres - reach, centres + reach]
        pts += [np.hstack(both_drums(f.curves)) for f in run.frames]
    allp = np.hstack(pts)
    lo, hi = allp.min(axis=1) - 0.01, allp.max(axis=1) + 0.01
    lo[2] = min(lo[2], -0.01)
    return np.column_stack([lo, hi])
