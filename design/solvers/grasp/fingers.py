"""Finger forces on the bird in 3-D, both drums (thesis §4.3; MODEL.md §4).

For every finger of the right drum at time t and bird pose (X, Z, θ): the
finger's frame on the drum and its contact with the bird, continued from the
finger's previous state, mapped back to the world. Two contact models:

* ``planar`` (the thesis's): the finger's bending plane cuts the bird in an
  ellipse, the 2-D contact is solved in it and only its in-plane force acts;
* ``spatial``: the finger is a rod bending about both section axes and
  twisting (design/physics/rod.py) against the whole ellipsoid; the force
  acts along the surface normal with 3-D Coulomb friction.

Every contact reports how far it leaves the finger's bending plane (the
out-of-plane shares of the surface normal and of the sweep), which is what
decides whether the planar model may be used. A contact that cannot be
solved raises :class:`ContactFailed`: the run stops there instead of
counting the finger's force as zero.

The left drum's finger is the mirror image: same force magnitudes, Y
components opposite, so the symmetric grasp sees twice the right drum's X
and Z forces and moment.

Model only what can touch: :func:`reach_windows` finds, from the undeformed
finger loci (eq. 5.1), the time windows in which a finger can reach the bird
at all; outside them no contact problem is built or solved, and inside them
none either while the straight finger misses the bird (:func:`straight_level`).

The belt. A finger whose straight tip would pass below the belt's surface
(design/physics/belt.py) rests on it: the belt pushes its tip up and drags
it with friction at the finger-belt µ against the tip's sliding over the
moving belt, and the bird meets the finger so bent. Such a finger is solved
with the belt while it is inside its reach windows. A finger pushed into
the belt by the bird is solved with the belt from then on.

First touch (spatial fingers). An integrator's trial evaluations continue
each contact from its last accepted state; a finger that did not touch the
bird there is left out of them (it presses nothing), and the accepted
instant that finds it inside the bird ends its step early: the integrator
locates where the finger's clearance (:meth:`FingerForces.touch_margin`)
crosses zero and accepts that instant instead, where the contact starts
(design/solvers/grasp/integrate.py). So no step has a contact starting
inside it, where the force's kink would make the stepper reject its step
again and again, each try solving the first touch afresh.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from functools import cached_property
from typing import NamedTuple

import numpy as np

from design.physics.belt import Belt
from design.physics.bird import Bird, Loads
from design.physics.contact import ContactSolution
from design.physics.ellipse import Ellipse
from design.physics.grasper import Grasper
from design.physics.kinematics import Ellipsoid
from design.solvers.contact import RobustContact
from design.solvers.contact.spatial import (FrictionLaw, Quadric, SpatialContact,
                                          SpatialSolution, SpatialState, segment_level)
from design.solvers.contact.belt_continuation import BELT_MODES, BIRD_MODES, Belted, Plane
from design.solvers.contact.planar_belt import PlanarBeltContact
from design.solvers.contact.spatial_belt import SpatialBeltContact
from design.solvers.grasp.views import finger_views

#: finite-difference step (s) for the rates the friction direction needs
RATE_STEP = 1e-6
#: a finger's friction reverses only when it slides the other way faster than
#: this (m/s): flipping it at every sign change of the sliding speed, decided
#: at accepted steps, chatters (the force jumps by tens of newtons every few
#: milliseconds)
REVERSAL_SPEED = 0.02
#: the spatial finger's Coulomb friction is regularised below this sliding
#: speed (m/s): F_t = -µ N v / sqrt(|v|² + ε²); the drum sweeps the fingers
#: past the bird at 0.1-0.5 m/s, so friction is within 1% of µ N above 0.14 m/s
FRICTION_SPEED = 0.02
#: the straight finger's least level function (dimensionless) above which it
#: certainly misses the bird and no contact is solved; nearer the surface each
#: finger model decides by its own test (the planar one from its section,
#: whose level differs from the ellipsoid's by rounding)
MISSES = 1e-9
#: :func:`clear_at`'s margins over MISSES (level) and over the belt (tip
#: height, m): far above any round-off of the two ways of computing them
CLEAR_LEVEL, CLEAR_HEIGHT = 1e-6, 1e-6
#: the friction-reversal margin (m/s) reported where no finger's friction can reverse
NO_REVERSAL = 1.0
#: a planar finger meets the belt only where its bending plane is at least this
#: far (rad) from the belt's plane: rigid out of its plane, it cannot bend onto
#: a belt nearly parallel to it
PLANAR_BELT_ANGLE = np.radians(3.0)


@dataclass
class FingerState:
    """One finger's contact at one instant (right drum), world frame.

    ``normal_out_of_plane`` and ``sweep_out_of_plane`` (0-1): the shares of
    the bird's surface normal and of the finger's sliding over the surface
    along the finger's stiff axis (see :meth:`FingerForces._shares`); nan in
    an integrator's trial evaluations, which only need the loads.
    """

    force: np.ndarray = field(default_factory=lambda: np.zeros(3))   # on the bird, N
    point: np.ndarray | None = None                                  # world, m
    body_point: np.ndarray | None = None                             # bird frame, m
    solution: ContactSolution | SpatialSolution | None = None
    normal_out_of_plane: float = 0.0
    sweep_out_of_plane: float = 0.0
    #: the contact solver's state, to continue or test from
    continued: object = None

    @property
    def magnitude(self) -> float:
        """|force| (N); 0 without a contact point (the force is then zero)."""
        return 0.0 if self.point is None else float(np.linalg.norm(self.force))

    @property
    def belt_force(self) -> float:
        """The finger's normal force on the belt (N; 0 off the belt)."""
        return float(getattr(self.solution, "belt_normal_force", 0.0))

    @property
    def lost(self) -> bool:
        """Whether its solve lost the equilibrium continued from the accepted
        state and found one afresh (a trial finds that at a coarser stall
        than a commit: design/solvers/contact/belt_continuation.py)."""
        return self.solution is not None and bool(self.solution.extras.get("continuation_lost"))


#: every finger out of reach, at every evaluation: one state, read-only
OUT_OF_REACH = FingerState()
OUT_OF_REACH.force.setflags(write=False)


class Latest(dict):
    """Values kept for the latest keys (times, instants) an integrator asks
    about again and again: emptied when it holds more than ``size``."""

    def __init__(self, size: int):
        super().__init__()
        self.size = size

    def kept(self, key, make):
        """The value at ``key``, made by ``make()`` where there is none yet."""
        if key in self:
            return self[key]
        if len(self) > self.size:
            self.clear()
        value = self[key] = make()
        return value


def reach_windows(grasper: Grasper, bird: Bird, speed: float, centre_path, t_end: float,
                  margin: float = 0.15, dt: float = 1e-3) -> list[list[tuple[float, float]]]:
    """Per finger, the time windows (s) in which its straight finger can touch
    the bird, padded by one sample.

    Conservative: the bird's centre is anywhere within ``margin`` (m) of
    ``centre_path(times)`` = (X, Z) (arrays, or Z a scalar) along X and
    between the conveyor and ``margin`` above the path in Z, and any
    orientation; a finger can touch only if its undeformed segment comes
    within the largest semi-axis of that region. Contact needs the straight
    finger to enter the bird, so outside these windows the force is zero.
    """
    drum = grasper.drum(speed)
    times = np.arange(0.0, t_end + dt, dt)
    reach = max(bird.eta, bird.lam, bird.gamma)
    x, z = np.broadcast_arrays(*(np.asarray(c, float) for c in centre_path(times)))
    x, top = x[:, None], z[:, None] + margin                          # (n, 1)
    s = np.linspace(0.0, 1.0, 24)[None, :]
    turns = drum.turning(times)
    out = []
    for gf in grasper.fingers:
        base0, R0 = drum.frame(gf.mount, 0.0)
        base = drum.origin + turns @ (base0 - drum.origin)
        axis = turns @ R0[:, 0] * gf.finger.length
        # the segment's points (n, 24) and their distances outside the region
        # [x - margin, x + margin] x {0} x [0, top], squared
        px, py, pz = (base[:, k, None] + s * axis[:, k, None] for k in range(3))
        gap2 = np.maximum(np.abs(px - x) - margin, 0.0) ** 2 + py ** 2 + \
            np.maximum(np.maximum(-pz, pz - top), 0.0) ** 2
        out.append(_windows(np.min(gap2, axis=1) <= reach ** 2, times, dt))
    return out


def clear_at(grasper: Grasper, bird: Bird, speed: float, fingers: list[int],
             probes: np.ndarray) -> bool:
    """Whether the straight fingers ``fingers`` (indices) stay clear of the
    bird and above the belt at every probe (t, X, Z, pitch) (s, m, m, rad;
    the bird's centre at (X, 0, Z)), with a margin for round-off: where
    :meth:`FingerForces.reaching` looks, it leaves them out."""
    if len(probes) == 0 or not fingers:
        return True
    t, x, z, pitch = np.asarray(probes, float).T
    drum = grasper.drum(speed)
    turns = drum.turning(t)
    centre = np.stack([x, np.zeros_like(x), z], axis=1)
    c, s = np.cos(pitch), np.sin(pitch)
    scale = np.array([1 / bird.eta, 1 / bird.lam, 1 / bird.gamma])

    def body(v):
        """World vectors (n, 3) in body coordinates (rot_y(pitch) transposed), scaled."""
        return scale * np.stack([c * v[:, 0] - s * v[:, 2], v[:, 1], s * v[:, 0] + c * v[:, 2]],
                                axis=1)
    for i in fingers:
        gf = grasper.fingers[i]
        base0, R0 = drum.frame(gf.mount, 0.0)
        base = drum.origin + turns @ (base0 - drum.origin)
        axis = turns @ R0[:, 0]
        level = scaled_level(body(base - centre), body(axis), gf.finger.length)
        tip_z = base[:, 2] + axis[:, 2] * gf.finger.length
        if np.any(level <= CLEAR_LEVEL) or np.any(tip_z <= CLEAR_HEIGHT):
            return False
    return True


def _windows(near: np.ndarray, times: np.ndarray, dt: float) -> list[tuple[float, float]]:
    """The runs of True in ``near`` as time windows padded by one sample."""
    windows = []
    k = 0
    while k < near.size:
        if near[k]:
            j = k
            while j + 1 < near.size and near[j + 1]:
                j += 1
            windows.append((max(0.0, times[k] - dt), times[j] + dt))
            k = j + 1
        else:
            k += 1
    return windows


class ContactFailed(RuntimeError):
    """A finger's contact could not be solved: the run cannot go on honestly
    (counting the finger's force as zero would lower the peak force)."""

    def __init__(self, t: float, finger: str, message: str):
        super().__init__(f"finger {finger}'s contact failed at t = {t:.4f} s: {message}")
        self.t, self.finger, self.reason = t, finger, message


class OverBudget(RuntimeError):
    """The belt continuations' Newton solves passed the run's
    budget (IntegratorSettings.max_newton_solves per simulated second): the
    run stops there, as soon as the count passes it after its first instant
    (which is always kept)."""

    def __init__(self, t: float, solves: int, per_second: float):
        super().__init__(f"stopped at t = {t:.4f} s: the belt continuations called Newton's "
                         f"method {solves} times, over the budget of {per_second:g} per "
                         f"simulated second")


class PlanarFinger:
    """The thesis's finger (§4.3): rigid out of its bending plane; the plane
    cuts the bird in an ellipse, the planar contact is solved in it and only
    its in-plane force acts (eq. 4.26: no force along z_f). Friction at the
    edge of sliding, reversed when the finger clearly slides the other way."""

    name = "planar"
    from_committed = False
    in_frames = False
    #: a trial may start a contact (continued from the latest trial's)
    touches_at_commits = False
    #: the friction's sense follows the finger's sliding (settled at accepted steps)
    settles_friction = True

    def __init__(self, finger, friction: float, intervals: int, degree: int,
                 reversal_speed: float = REVERSAL_SPEED):
        self.solver = RobustContact(finger, friction, intervals=intervals, degree=degree,
                                    reversal_speed=reversal_speed)
        self.reverses = friction > 0 and self.settles_friction
        self._belted: PlanarBeltContact | None = None

    @property
    def belted(self) -> PlanarBeltContact:
        """The solver with the belt (built on first use: most fingers never need it)."""
        if self._belted is None:
            self._belted = PlanarBeltContact(self.solver)
        return self._belted

    def reversal_margin(self, state, kin_factory) -> float:
        """:meth:`RobustContact.reversal_margin` of a contact state (m/s)."""
        state = state.with_ellipse()
        return self.solver.reversal_margin(state, kin_factory(state.ellipse))

    def solve(self, body: Ellipsoid, base, R, kin_factory, start, commit: bool, belt=None):
        """(force on the bird (3,) world, contact point (3,) world, solution,
        state to continue from); force None when the plane misses the bird.
        A trial evaluation continued from a contact is first tried in one
        Newton solve (:meth:`RobustContact.continue_trial`). ``belt``:
        (plane, friction law) in the finger frame where the finger may meet
        the belt, else None; the planar finger meets it in its bending plane
        (:meth:`_line`)."""
        line = self._line(belt)
        length = self.solver.finger.length
        resting = line is not None and line[0].level(np.array([[length], [0.0]]))[0] < 0.0
        if isinstance(start, Belted) and not (resting or start.mode in BELT_MODES):
            start = self.belted.bird_only(start)         # off the belt: the bird-only solver
        if line is not None and (isinstance(start, Belted) or resting):
            return self._belted_solve(body, base, R, kin_factory,
                                      start if isinstance(start, Belted) else None, commit, line)
        start = None if isinstance(start, Belted) else start
        if not commit and start is not None:
            center, B, rhs = body.section(base, R)
            trial = self.solver.continue_trial(start, center, B) if rhs > 0.0 else None
            if trial is not None:
                return self._checked(body, base, R, kin_factory, commit, line, *trial)
        cut = body.cut(base, R)
        if cut is None:
            return None, None, None, None
        made = []

        def kin(p_f):
            # built on first use: only a committed solve settles its friction
            # from the sliding, and building it (two finger frames and the bird
            # a step on) took a fifth of a trial evaluation's time
            if not made:
                made.append(kin_factory(cut))
            return made[0](p_f)

        sol, cont = self.solver.solve_frame(cut, "auto", kin if self.settles_friction else None,
                                            start, settle=commit, detail=commit)
        return self._checked(body, base, R, kin_factory, commit, line, sol, cont)

    def _checked(self, body, base, R, kin_factory, commit, line, sol, cont):
        """A bird-only solution, or, where it pushes the tip below the belt,
        the solution with the belt continued from it."""
        if line is not None and sol.contact and cont is not None:
            psi, arc = sol.psi, sol.arc_length
            tip = np.asarray(sol.point) + (self.solver.finger.length - arc) * np.array(
                [np.cos(psi), np.sin(psi)])
            if line[0].level(tip[:, None])[0] < 0.0:
                start = self.belted.adopt(cont, *line)
                return self._belted_solve(body, base, R, kin_factory, start, commit, line)
        return self._world(base, R, sol, cont)

    @staticmethod
    def _line(belt) -> tuple[Plane, np.ndarray] | None:
        """The belt in the bending plane: its line and friction law ([µ, ε,
        a (2), G (4)]: the finger's in-plane sliding over the belt, a + G p);
        None without a belt, or where the bending plane lies within
        PLANAR_BELT_ANGLE of the belt's (the planar finger, rigid out of its
        plane, cannot bend onto it)."""
        if belt is None:
            return None
        plane, law = belt
        size = float(np.linalg.norm(plane.normal[:2]))
        if size < np.sin(PLANAR_BELT_ANGLE):
            return None
        law = FrictionLaw.of(law)
        return Plane(plane.normal[:2] / size, plane.offset / size), np.concatenate(
            [[law.mu, law.speed], law.sliding_at_origin[:2], law.sliding_gradient[:2, :2].ravel()])

    def _belted_solve(self, body, base, R, kin_factory, start, commit, line):
        """The finger with the belt; the bird's section by the bending plane,
        where the plane cuts the bird (its continuation finds where the bent
        finger first meets it)."""
        center, B, rhs = body.section(base, R)
        conic = (center, B) if rhs > 0.0 else None
        tau_mu = self._bird_friction(start, conic, kin_factory, body, base, R)
        sol, cont = self.belted.solve(conic, tau_mu, *line, previous=start, detail=commit)
        return self._world(base, R, sol, cont)

    def _bird_friction(self, start, conic, kin_factory, body, base, R) -> float:
        """The bird's signed friction τµ for a finger on the belt: the
        contact's own while it lasts, else from the rigid finger's sliding
        over the bird where the straight finger comes nearest to it."""
        mu = self.solver.mu
        if mu == 0.0 or conic is None:
            return 0.0
        if not self.settles_friction:
            return mu
        if start is not None and start.mode in BIRD_MODES:
            return float(start.friction[0])
        center, B = conic
        x = float(np.clip(center[0] + B[0, 1] * center[1] / B[0, 0], 0.0,
                          self.solver.finger.length))
        v_object = kin_factory(body.cut(base, R))(np.array([x, 0.0]))[1]
        return mu if v_object[0] >= 0.0 else -mu

    @staticmethod
    def _world(base, R, sol, cont):
        if not sol.contact:
            return np.zeros(3), None, sol, cont
        f_w = R[:, :2] @ sol.force_on_object_finger_frame
        p_w = base + R[:, :2] @ np.asarray(sol.point)
        return f_w, p_w, sol, cont


class SpatialFinger:
    """The finger as a spatial rod (design/physics/rod.py): it bends about both
    section axes and twists, so the contact force acts along the bird's
    surface normal, with Coulomb friction opposite to the finger's sliding
    over the surface, regularised below FRICTION_SPEED.

    The sliding velocity is the rigid finger's (carried by the drum) relative
    to the bird's surface, at the contact point solved together with the
    force (:class:`FrictionLaw`); the finger's own deflection rate is left
    out. So the friction is a smooth function of the bird's state and time
    alone. (Taking the contact point from the previous solution instead makes
    the loads jump at every accepted step: the drum turns the finger's
    velocity by its angular speed times the point's shift, ε amplifies that,
    and the adaptive integrator's steps collapse.)
    :meth:`SpatialContact.sliding_velocity` gives the full material velocity
    for comparison.
    """

    name = "spatial"
    from_committed = True
    #: solves with the bird in its frame computed with the other fingers' (FrameViews)
    in_frames = True
    #: friction solved with the contact, regularised: nothing to reverse
    reverses = False
    #: no trial starts a contact: an integrator step ends where one starts
    #: (:meth:`FingerForces.touch_margin`), and the accepted instant starts it
    touches_at_commits = True

    def __init__(self, finger, friction: float, intervals: int, degree: int):
        self.solver = SpatialContact(finger, intervals=intervals, degree=degree)
        self.mu = float(friction)
        self._belted: SpatialBeltContact | None = None

    @property
    def belted(self) -> SpatialBeltContact:
        """The solver with the belt (built on first use: most fingers never need it)."""
        if self._belted is None:
            self._belted = SpatialBeltContact(self.solver)
        return self._belted

    def solve(self, view: "FrameView", base, R, start, commit: bool, belt=None):
        """As :meth:`PlanarFinger.solve`, with the bird as the finger's frame
        sees it (``view``, computed with the other fingers': :class:`FrameViews`)
        instead of the bird and its kinematics; ``belt``: (plane, friction
        law) in the finger frame where the finger may meet the belt, else
        None."""
        quadric = view.quadric
        resting = self._resting(belt)
        if isinstance(start, Belted) and not (resting or start.mode in BELT_MODES):
            start = self.belted.bird_only(start)         # off the belt: the bird-only solver
        if belt is not None and (resting or isinstance(start, Belted)):
            return self._belted_solve(quadric, self._law(view.motion), base, R,
                                      start if isinstance(start, Belted) else None, commit, belt)
        if view.level >= 0.0:
            return None, None, None, None
        start = start if isinstance(start, SpatialState) else None
        law = self._law(view.motion)
        sol, cont = self.solver.solve(quadric, law, start, detail=commit, level=view.level)
        if belt is not None and sol.contact and cont is not None and \
                belt[0].level(self._tip(sol, cont)[:, None])[0] < 0.0:
            # pushed into the belt by the bird: solved with it from the bird-only state
            return self._belted_solve(quadric, law, base, R, self.belted.adopt(cont, *belt),
                                      commit, belt)
        if not sol.contact:
            return np.zeros(3), None, sol, cont
        return R @ sol.force, base + R @ sol.point, sol, cont

    def _resting(self, belt) -> bool:
        """Whether the straight finger's tip is below the belt (``belt``: plane
        and law in the finger frame, or None)."""
        # the plane's level at (L, 0, 0): n_x L - e
        return belt is not None and \
            belt[0].normal[0] * self.solver.finger.length - belt[0].offset < 0.0

    @staticmethod
    def touching(state) -> bool:
        """Whether a solved state presses on the bird."""
        return isinstance(state, SpatialState) or (isinstance(state, Belted)
                                                   and state.mode in BIRD_MODES)

    def clearance(self, body: Ellipsoid, base, R, start, belt=None) -> float | None:
        """How far (m) the finger, not touching the bird at ``start``, is clear
        of it (< 0: inside, where :meth:`solve` starts the contact): the
        straight finger's, or the finger's on the belt solved in its mode;
        None where that cannot be said without solving the contact."""
        quadric = body_quadric(body, base, R)
        resting = self._resting(belt)
        if isinstance(start, Belted) and (resting or start.mode in BELT_MODES):
            if belt is None:
                return None
            target = Belted("free", None, quadric.params, start.friction, belt[0],
                            FrictionLaw.of(belt[1]).params)
            return self.belted.clearance(start, target)
        if resting:
            return None
        level = segment_level(quadric, self.solver.finger.length)
        return level / (2.0 * np.sqrt(np.linalg.eigvalsh(quadric.matrix).max()))

    def detailed(self, sol: SpatialSolution, state) -> tuple[SpatialSolution, object]:
        """A trial's solve with the detail its commit adds (the finger's shape,
        the continuation's Jacobian factors): what :meth:`solve` with
        ``commit`` returns from the same start at the same instant."""
        solver = self.belted if isinstance(state, Belted) else self.solver
        return solver.detailed(sol, state)

    def _law(self, motion: "SurfaceMotion") -> FrictionLaw:
        """The bird's friction law in the finger frame: regularised Coulomb
        against the rigid finger's sliding over the bird's surface (its
        ``motion`` relative to the frame)."""
        if self.mu <= 0:
            return FrictionLaw()
        return FrictionLaw(mu=self.mu, speed=FRICTION_SPEED, sliding_at_origin=-motion.v0,
                           sliding_gradient=-motion.gradient)

    def _tip(self, sol: SpatialSolution, state: SpatialState) -> np.ndarray:
        """The finger's tip (finger frame) in a bird-only contact."""
        post = state.post
        return post[:3] + post[13:16] * (self.solver.finger.length - post[4])

    def _belted_solve(self, quadric, law, base, R, start, commit, belt):
        """The finger with the belt and the bird (its continuation finds where
        the bent finger first meets the bird)."""
        sol, cont = self.belted.solve(quadric, law, belt[0], belt[1], start, detail=commit,
                                      trial=not commit)
        if not sol.contact:
            return np.zeros(3), None, sol, cont
        return R @ sol.force, base + R @ sol.point, sol, cont


class ThesisPlanarFinger(PlanarFinger):
    """The planar finger with the thesis's chapter III friction convention:
    friction on the finger at µ, pointing tipwards, whatever the sliding (what
    its Algorithms I and II and Tables 3-2 to 3-5 use). For reproducing the
    thesis's own simulations: its FEM (Table 3-6) follows friction from the
    sliding, as ``planar`` does (the pass's peak: FEM 31.8 N, ``planar``'s
    friction 31.0 N, this convention 24.5 N)."""

    name = "planar-thesis"
    settles_friction = False


#: contact models by name
FINGER_MODELS = {m.name: m for m in (PlanarFinger, ThesisPlanarFinger, SpatialFinger)}


class SurfaceMotion:
    """The bird's motion in a finger frame over RATE_STEP (spatial fingers):
    its surface's velocity relative to the frame, affine in the point, v(p)
    = v0 + gradient p (m/s, finger frame), and the rates of its quadric's
    parameters (computed when first asked for); called with a point, the
    pair (rates, v(p)) (design.solvers.contact.spatial.Kinematics)."""

    def __init__(self, v0: np.ndarray, gradient: np.ndarray, rates):
        self.v0, self.gradient, self._rates = v0, gradient, rates

    @cached_property
    def rates(self) -> np.ndarray:
        return self._rates()

    def __call__(self, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return self.rates, self.v0 + self.gradient @ p


def straight_level(body: Ellipsoid, base: np.ndarray, axis: np.ndarray, length):
    """min over the straight finger (base + x axis, 0 ≤ x ≤ length) of the
    bird's level function |D q|² - 1, q in body coordinates, D = diag(1/η,
    1/λ, 1/γ): a parabola in x. < 0 when the straight finger enters the bird.
    For n fingers at once: base and axis (n, 3), length (n,); returns (n,)."""
    scale = np.array([1 / body.eta, 1 / body.lam, 1 / body.gamma])
    return scaled_level(scale * ((base - np.asarray(body.center)) @ body.rotation),
                        scale * (axis @ body.rotation), length)


def scaled_level(p: np.ndarray, e: np.ndarray, length):
    """min over 0 ≤ x ≤ length of |p + x e|² - 1: the straight finger's level
    from its base p and axis e in the bird's scaled body coordinates (n, 3)."""
    x = np.clip(-np.sum(p * e, axis=-1) / np.sum(e * e, axis=-1), 0.0, length)
    q = p + x[..., None] * e
    return np.sum(q * q, axis=-1) - 1.0


def body_quadric(body: Ellipsoid, base: np.ndarray, R: np.ndarray) -> Quadric:
    """The bird's ellipsoid in a finger frame (base, R) as a quadric."""
    Rb = R.T @ body.rotation
    return Quadric(R.T @ (np.asarray(body.center, float) - base), Rb @ body.matrix @ Rb.T)


class FrameView(NamedTuple):
    """The bird in one finger's frame at one instant (spatial fingers): its
    quadric, the straight finger's level in it (:func:`segment_level`) and
    its surface's motion relative to the frame."""

    quadric: Quadric
    level: float
    motion: SurfaceMotion


class FrameViews:
    """Every finger's :class:`FrameView` at one instant, computed together:
    ``frames`` (bases (n, 3), rotations (n, 3, 3)) at time t with the bird
    ``body``, ``frames_later`` and the bird ``later`` dt on (the surface's
    motion is their forward difference: a point p of the finger frame is
    carried with the bird to t + dt and seen in the finger's frame then,
    affine in p); ``lengths`` (n,) m. Index with a finger's number."""

    def __init__(self, body: Ellipsoid, later: Ellipsoid, dt: float, frames, frames_later,
                 lengths: np.ndarray):
        self.centres, self.matrices, self.levels, self.v0, self.gradients = finger_views(
            body, later, dt, frames, frames_later, lengths)
        self._later = (later, frames_later, dt)
        self._views: dict[int, FrameView] = {}

    def __getitem__(self, k: int) -> FrameView:
        view = self._views.get(k)
        if view is None:
            quadric = Quadric(self.centres[k], self.matrices[k])
            view = self._views[k] = FrameView(quadric, float(self.levels[k]), SurfaceMotion(
                self.v0[k], self.gradients[k], lambda: self._rates(k, quadric)))
        return view

    def _rates(self, k: int, quadric: Quadric) -> np.ndarray:
        """The rates of finger k's quadric parameters (forward difference)."""
        later, (bases2, R2), dt = self._later
        return (body_quadric(later, bases2[k], R2[k]).params - quadric.params) / dt


def _nearer(accepted, trial):
    """The state to continue a spatial finger's contact from instead of the
    accepted one for :meth:`FingerForces.varied`: the trial's, where that is
    of the accepted state's kind and has Jacobian factors of its own or is
    in the accepted state's mode (it then takes the accepted state's
    factors), else the accepted state."""
    if trial is None or type(trial) is not type(accepted):
        return accepted
    if trial.lu is not None:
        return trial
    return replace(trial, lu=accepted.lu) if trial.mode == accepted.mode else accepted


class FingerForces:
    """All fingers' forces on the bird, continued in time finger by finger.

    ``evaluate(t, y, commit)`` returns the summed loads and each finger's
    state. Trial evaluations (``commit`` false) keep each contact's friction
    from the last committed state; committed ones (accepted integrator
    steps) also decide it from the sliding velocity and become the states
    later evaluations continue from. A contact that cannot be solved raises
    :class:`ContactFailed`.
    """

    def __init__(self, grasper: Grasper, bird: Bird, drum_speed: float, friction: float,
                 windows: list[list[tuple[float, float]]] | None = None,
                 intervals: int = 8, degree: int = 4, model: str = "planar",
                 belt: Belt = Belt(), belt_friction: float = 0.0):
        self.grasper, self.bird = grasper, bird
        self.belt, self.belt_friction = belt, float(belt_friction)
        #: the belt's speed (m/s) at time t; the grasp that drives the belt sets it
        self.belt_speed = lambda t: 0.0
        self.drum = grasper.drum(drum_speed)
        kind = FINGER_MODELS[model]
        self.models = [kind(gf.finger, friction, intervals, degree) for gf in grasper.fingers]
        #: a commit may reuse the trial at its instant (:meth:`_commit_trial`)
        self._trials_from_committed = kind.from_committed
        self._in_frames = kind.in_frames
        self.states: list = [None] * len(grasper.fingers)    # at the last accepted step
        self.trials: list = [None] * len(grasper.fingers)    # at the latest evaluation
        self.solves = 0            # contact problems solved
        self.skipped = 0           # finger evaluations the reach windows saved
        #: every instant :meth:`reaching` looked at, (t, X, Z, pitch) (s, m, m,
        #: rad), and the fingers it ever found reaching: a finger clear at
        #: each of them adds nothing to the run (:func:`clear_at`)
        self.probes: list[tuple[float, float, float, float]] = []
        self.reached: set[int] = set()
        #: (the run's most belt-continuation Newton solves, the budget per
        #: simulated second) or None: no budget (:class:`OverBudget`)
        self.budget: tuple[float, float] | None = None
        self._memo: dict = {}      # trial evaluations since the last commit
        #: the fingers whose contact with the bird the latest commit started
        #: (:meth:`touch_margin`)
        self.touched: list[int] = []
        self._committed = False    # an instant accepted
        self._margins: dict = {}   # (t, y) -> reversal margin, for the latest evaluations
        self._frames = Latest(64)    # t -> every finger's frame
        self._belts = Latest(256)    # (finger, t, belt speed) -> the belt it sees
        self._frame_views = Latest(16)    # (t, y) -> FrameViews
        self._inside = Latest(64)    # t -> the fingers to look at
        start = [self.drum.frame(gf.mount, 0.0) for gf in grasper.fingers]
        self._base0 = np.array([base for base, _ in start])
        self._R0 = np.array([R for _, R in start])
        self._lengths = np.array([gf.finger.length for gf in grasper.fingers])
        # every window's start, end and finger, for a vectorised test
        spans = [(a, b, i) for i, w in enumerate(windows or []) for a, b in w]
        self._window_ends = None if windows is None else (
            np.array([a for a, _, _ in spans], float), np.array([b for _, b, _ in spans], float),
            np.array([i for _, _, i in spans], int))

    def frames(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        """Every finger's base (n, 3) and rotation (n, 3, 3) at time t: their
        frames at t = 0 turned with the drum. An evaluation asks for the same
        time several times (reach, contact, rates at t + RATE_STEP, shares);
        the arrays are shared, hence read-only."""
        def make():
            turn = self.drum.turning(t)
            origin = self.drum.origin
            out = (origin + (self._base0 - origin) @ turn.T, turn @ self._R0)
            for a in out:
                a.setflags(write=False)
            return out
        return self._frames.kept(t, make)

    def frame(self, i: int, t: float) -> tuple[np.ndarray, np.ndarray]:
        """Finger i's (base, R) at time t (:meth:`frames`)."""
        bases, rotations = self.frames(t)
        return bases[i], rotations[i]

    def reaching(self, t: float, y: np.ndarray, body: Ellipsoid) -> set[int]:
        """The fingers to solve at (t, y), among those inside their reach
        windows (the others count as skipped): those whose straight line
        enters the bird (level ≤ MISSES; spatial fingers: the level in
        their views, :class:`FrameViews`), and those resting on the belt
        (the straight tip below it), which the bird may meet bent: every
        evaluation solves the same ones, so that a trial sees what the
        accepted instant will."""
        self.probes.append((t, body.center[0], body.center[2], body.pitch))
        inside, resting = self._candidates(t)
        self.skipped += len(self.models) - inside.size
        if inside.size == 0:
            return set()
        if self._in_frames:
            levels = self._views(t, y, body).levels[inside]
        else:
            bases, rotations = self.frames(t)
            levels = straight_level(body, bases[inside], rotations[inside, :, 0],
                                    self._lengths[inside])
        out = set(inside[levels <= MISSES].tolist()) | resting
        self.reached |= out
        return out

    def _candidates(self, t: float) -> tuple[np.ndarray, set[int]]:
        """The fingers inside their reach windows at time t, and those of them
        resting on the belt (the straight tip below it, where the finger
        meets it), kept for the latest times, as :meth:`frames` is."""
        def make():
            if self._window_ends is None:
                inside = np.arange(len(self.models))
            else:
                lo, hi, owner = self._window_ends
                inside = np.unique(owner[(lo <= t) & (t <= hi)])
            resting = set()
            if inside.size:
                bases, rotations = self.frames(t)
                tips = bases[inside] + rotations[inside, :, 0] * self._lengths[inside][:, None]
                below = tips[:, 2] < 0
                resting = {int(i) for i, tip in zip(inside[below], tips[below])
                           if self.belt.touches(self.grasper.fingers[i].design_name, tip[1])}
            return inside, resting
        return self._inside.kept(t, make)

    def belt_contact(self, i: int, t: float) -> tuple[Plane, FrictionLaw] | None:
        """The belt as finger i sees it at time t: the plane Z = 0 and the
        friction law against the finger's sliding over the moving belt, in
        the finger frame; None where the finger passes beside it or through
        a slot (judged at its straight tip). Kept for the latest times, as
        :meth:`frames` is."""
        speed = self.belt_speed(t)

        def make():
            out = self._belt_contact(i, t, speed)
            for a in () if out is None else (out[0].normal, *vars(out[1]).values()):
                if isinstance(a, np.ndarray):
                    a.setflags(write=False)
            return out
        return self._belts.kept((i, t, speed), make)

    def _belt_contact(self, i: int, t: float, speed: float) -> tuple[Plane, FrictionLaw] | None:
        base, R = self.frame(i, t)
        tip = base + R[:, 0] * self._lengths[i]
        if not self.belt.touches(self.grasper.fingers[i].design_name, tip[1]):
            return None
        plane = Plane(R[2].copy(), -float(base[2]))
        if self.belt_friction <= 0.0:
            return plane, FrictionLaw()
        dt = RATE_STEP
        base2, R2 = self.frame(i, t + dt)
        belt = np.array([speed * dt, 0.0, 0.0])
        # the belt's material velocity relative to the finger frame at r: v0 + G r
        v0 = R2.T @ (base + belt - base2) / dt
        G = (R2.T @ R - np.eye(3)) / dt
        return plane, FrictionLaw(mu=self.belt_friction, speed=FRICTION_SPEED,
                                  sliding_at_origin=-v0, sliding_gradient=-G)

    @property
    def newton_solves(self) -> int:
        """The belt continuations' Newton solves so far, every
        finger's (the costly part of a run's contact work, where the chord
        method did not converge): the same count on every machine."""
        return sum(0 if m._belted is None else m._belted.newton_total for m in self.models)

    def ellipsoid(self, y: np.ndarray) -> Ellipsoid:
        b = self.bird
        return Ellipsoid(b.eta, b.lam, b.gamma, (y[0], 0.0, y[1]), y[2])

    def evaluate(self, t: float, y: np.ndarray, commit: bool = False
                 ) -> tuple[Loads, list[FingerState]]:
        key = (t, y.tobytes())
        memo = self._memo.get(key)
        if not commit and memo is not None:
            return memo[0]
        waiting = self._waiting() if commit else set()
        if commit and memo is not None and self._trials_from_committed and \
                not any(st.lost for st in memo[0][1]):
            out, skipped = self._commit_trial(t, y, *memo), ()
        else:
            out, skipped = self._evaluate(t, y, commit)
        if self.budget is not None and t > 0.0 and (solves := self.newton_solves) > self.budget[0]:
            raise OverBudget(t, solves, self.budget[1])
        if commit:
            self.touched = [i for i in waiting if self.models[i].touching(self.states[i])]
            self._committed = True
            self._memo.clear()
            self._margins.clear()
        elif len(self._memo) > 16:
            self._memo.pop(next(iter(self._memo)))
        self._memo[key] = out, skipped
        return out

    def _waiting(self, among=None) -> set[int]:
        """The fingers (``among`` these indices, else all) whose contact starts
        only at an accepted instant (``touches_at_commits``) that did not
        touch the bird at the last one (none before the first: a bird may
        start in the fingers)."""
        if not self._committed:
            return set()
        return {i for i in (range(len(self.models)) if among is None else among)
                if self.models[i].touches_at_commits
                and not self.models[i].touching(self.states[i])}

    def touch_margin(self, t: float, y: np.ndarray) -> float:
        """The least clearance (m) from the bird at (t, y) of the fingers
        waiting for a contact to start (:meth:`_waiting`) inside their reach
        windows (inf: none can say). Below zero one of them touches: its
        trials leave it out, so the integrator ends its step there and the
        accepted instant starts the contact."""
        body = self.ellipsoid(y)
        waiting = self._waiting()
        margins = [self.models[i].clearance(body, *self.frame(i, t), self.states[i],
                                            self.belt_contact(i, t))
                   for i in sorted(self.reaching(t, y, body) & waiting)]
        return min([np.inf] + [m for m in margins if m is not None])

    def _evaluate(self, t: float, y: np.ndarray, commit: bool
                  ) -> tuple[tuple[Loads, list[FingerState]], list[int]]:
        """Every finger solved at (t, y): (loads, states), and the fingers a
        trial left out, waiting for their contact to start at an accepted
        instant."""
        body = self.ellipsoid(y)
        loads = Loads()
        reaching = self.reaching(t, y, body)
        skipped = [] if commit else sorted(self._waiting(reaching))
        states = [self._no_contact(i, commit) if i not in reaching or i in skipped
                  else OUT_OF_REACH for i in range(len(self.models))]
        for i in sorted(reaching.difference(skipped)):
            states[i] = self._state(i, t, y, body, self._solve(i, t, y, body, commit), commit,
                                    loads)
        return (loads, states), skipped

    def _solve(self, i: int, t: float, y: np.ndarray, body: Ellipsoid, commit: bool):
        """Finger i's model solved at (t, y): (force, point, solution, state)."""
        base, R = self.frame(i, t)
        # continue from the latest solution, trial or committed: the nearest
        # in time (trials keep the committed friction); or, for a model whose
        # friction is solved with the contact (spatial), always from the
        # committed one, so that trials cannot wander onto another branch
        model = self.models[i]
        start = self.states[i] if commit or model.from_committed else self.trials[i]
        belt = self.belt_contact(i, t)
        if self._in_frames:
            return model.solve(self._views(t, y, body)[i], base, R, start, commit, belt)
        return model.solve(body, base, R, lambda shape: self._kinematics(i, t, y, shape), start,
                           commit, belt)

    def _views(self, t: float, y: np.ndarray, body: Ellipsoid) -> FrameViews:
        """The bird in every finger's frame at (t, y), kept for the latest instants."""
        def make():
            later = y.copy()
            later[:3] += RATE_STEP * y[3:]
            return FrameViews(body, self.ellipsoid(later), RATE_STEP, self.frames(t),
                              self.frames(t + RATE_STEP), self._lengths)
        return self._frame_views.kept((t, y.tobytes()), make)

    def _state(self, i: int, t: float, y: np.ndarray, body: Ellipsoid, solved, commit: bool,
               loads: Loads) -> FingerState:
        """Finger i's state from its solve (None: not solved, out of reach),
        its force added to ``loads`` (both drums)."""
        force, p_w, sol, cont = solved or (None,) * 4
        if force is None:                           # out of reach: no contact problem
            return self._no_contact(i, commit)
        self.solves += 1
        state = self._kept(i, t, y, body, force, p_w, sol, cont, commit)
        if p_w is not None:
            r = p_w - np.array([y[0], 0.0, y[1]])
            loads.qx += 2 * force[0]
            loads.qz += 2 * force[2]
            loads.ty += 2 * (r[2] * force[0] - r[0] * force[2])
        return state

    def _no_contact(self, i: int, commit: bool) -> FingerState:
        """Finger i out of reach (or left out): no contact to continue from."""
        self.trials[i] = None
        if commit:
            self.states[i] = None
        return OUT_OF_REACH

    def _kept(self, i: int, t: float, y: np.ndarray, body: Ellipsoid, force: np.ndarray,
              p_w: np.ndarray | None, sol, cont, commit: bool) -> FingerState:
        """Finger i's solve at (t, y) as its state, kept to continue from (and
        committed); a solve that did not converge raises :class:`ContactFailed`."""
        if not sol.converged:
            raise ContactFailed(t, self.grasper.fingers[i].name, sol.message)
        self.trials[i] = cont
        if commit:
            self.states[i] = cont
        if p_w is None:
            return FingerState(solution=sol, continued=cont)
        shares = self._shares(i, t, y, body, p_w) if commit else (np.nan, np.nan)
        r = p_w - np.array([y[0], 0.0, y[1]])
        return FingerState(force, p_w, body.rotation.T @ r, sol, *shares, cont)

    def _commit_trial(self, t: float, y: np.ndarray, trial: tuple[Loads, list[FingerState]],
                      skipped: list[int]) -> tuple[Loads, list[FingerState]]:
        """Commit the trial evaluation at (t, y): where every trial continues
        from the committed contacts (``from_committed``), the trial solved
        what the commit would (not where one lost its continued equilibrium,
        which a trial finds at a coarser stall: the commit then solves
        every finger again), and the commit only adds each solve's detail
        and each contact's out-of-plane shares, and solves the fingers the
        trial left out (``skipped``). (An adaptive Runge-Kutta step's last
        stage is evaluated where the step ends, the instant then accepted.)"""
        loads, trial_states = trial
        loads = replace(loads)
        body = self.ellipsoid(y)
        states = []
        for i, st in enumerate(trial_states):
            if i in skipped:
                states.append(self._state(i, t, y, body, self._solve(i, t, y, body, True), True,
                                          loads))
            elif st.solution is None:                 # out of reach
                self.trials[i] = self.states[i] = None
                states.append(st)
            else:
                sol, cont = self.models[i].detailed(st.solution, st.continued)
                states.append(self._kept(i, t, y, body, st.force, st.point, sol, cont, True))
        return loads, states

    def varied(self, t: float, y: np.ndarray, near: tuple[float, np.ndarray]) -> Loads:
        """The loads at (t, y), a trial evaluation whose contacts continue
        from their trial at the instant ``near`` (t, y) a hair away (an
        integrator's difference quotient) instead of from the accepted state:
        the same contacts, found from much nearer (planar fingers continue
        from their latest trial, as all their trials do). Leaves this object
        as it was."""
        key = (near[0], near[1].tobytes())
        if key not in self._memo:
            self.evaluate(*near)
        (_, trials), _ = self._memo[key]
        starts = [_nearer(state, trial.continued) for state, trial in zip(self.states, trials)] \
            if self._trials_from_committed else self.states
        kept = self.states, self.trials, self._memo, self._margins
        self.states, self.trials = starts, list(self.trials)
        self._memo, self._margins = {}, {}
        try:
            return self._evaluate(t, y, commit=False)[0][0]
        finally:
            self.states, self.trials, self._memo, self._margins = kept

    def probe(self, t: float, y: np.ndarray, snapshot: tuple[list, list]) -> list[FingerState]:
        """The fingers' states at (t, y), a trial evaluation continued from an
        earlier :meth:`snapshot`, leaving this object exactly as it was (a
        look inside an accepted step that changes nothing after it)."""
        kept = self.states, self.trials, self._memo, self._margins
        self.states, self.trials = list(snapshot[0]), list(snapshot[1])
        self._memo, self._margins = {}, {}
        try:
            return self._evaluate(t, y, commit=False)[0][1]
        finally:
            self.states, self.trials, self._memo, self._margins = kept

    def snapshot(self) -> tuple[list, list]:
        """The contacts to continue from (accepted and latest), to go back to."""
        return list(self.states), list(self.trials)

    def restore(self, snapshot: tuple[list, list]) -> None:
        """Go back to a :meth:`snapshot`: an accepted instant is withdrawn."""
        self.states, self.trials = list(snapshot[0]), list(snapshot[1])
        self._memo.clear()
        self._margins.clear()

    def reversal_margin(self, t: float, y: np.ndarray) -> float:
        """The least friction-reversal margin (m/s, :meth:`PlanarFinger.
        reversal_margin`) of the fingers touching the bird at (t, y) with the
        friction of their last accepted contact; NO_REVERSAL where none can
        reverse. Below zero a finger's friction turns: the integrator, finding
        a friction turned at an accepted instant, locates where within the
        step it did and accepts that instant instead. (A finger that touches
        again after a trial without contact starts from first touch with a
        guessed friction, which the next accepted instant settles: not a
        reversal.) A finger on the belt keeps its friction's sense
        (design/solvers/contact/planar_belt.py)."""
        key = (t, y.tobytes())
        if key not in self._margins:
            if len(self._margins) > 16:
                self._margins.clear()
            _, states = self.evaluate(t, y)
            self._margins[key] = min([NO_REVERSAL] + [
                self.models[i].reversal_margin(st.continued, lambda shape, i=i: self._kinematics(
                    i, t, y, shape))
                for i, st in enumerate(states)
                if self.models[i].reverses and st.point is not None and st.continued is not None
                and self.states[i] is not None and not isinstance(st.continued, Belted)
                and not isinstance(self.states[i], Belted)
                and st.continued.tau_mu == self.states[i].tau_mu])
        return self._margins[key]

    def _shares(self, i: int, t: float, y: np.ndarray, body: Ellipsoid, p_w: np.ndarray
                ) -> tuple[float, float]:
        """How far a contact leaves the finger's bending plane: the share of the
        bird's surface normal along the stiff axis z_f, |n·z_f|, and of the
        finger's sweep over the surface, |v·z_f| / |v| (v the rigid finger's
        velocity relative to the bird's surface at the contact)."""
        base, R = self.frame(i, t)
        p_b = body.rotation.T @ (p_w - np.asarray(body.center))
        n = body.rotation @ (body.matrix @ p_b)
        n /= np.linalg.norm(n)
        dt = RATE_STEP
        base2, R2 = self.frame(i, t + dt)
        frame_v = (base2 + R2 @ (R.T @ (p_w - base)) - p_w) / dt
        y2 = y.copy()
        y2[:3] += dt * y[3:]
        body2 = self.ellipsoid(y2)
        object_v = (np.asarray(body2.center) + body2.rotation @ p_b - p_w) / dt
        v = frame_v - object_v
        v -= (v @ n) * n
        speed = np.linalg.norm(v)
        return float(abs(n @ R[:, 2])), float(abs(v @ R[:, 2]) / speed) if speed > 0 else 0.0

    def _kinematics(self, i: int, t: float, y: np.ndarray, cut: Ellipse):
        """Rates of the bird's section ``cut`` (a planar finger's ellipse) in
        finger i's frame, and the bird's surface velocity relative to that
        frame, by a forward difference over RATE_STEP (spatial fingers:
        :class:`FrameViews`)."""
        dt = RATE_STEP
        y2 = y.copy()
        y2[:3] += dt * y[3:]
        base, R = self.frame(i, t)
        base2, R2 = self.frame(i, t + dt)
        body, body2 = self.ellipsoid(y), self.ellipsoid(y2)

        def surface_velocity(p_f: np.ndarray) -> np.ndarray:
            p3 = np.concatenate([p_f, [0.0]])
            p_w = base + R @ p3
            p_b = body.rotation.T @ (p_w - np.array(body.center))
            p_w2 = np.array(body2.center) + body2.rotation @ p_b
            return (R2.T @ (p_w2 - base2) - p3) / dt

        def kin(p_f: np.ndarray):
            cut2 = body2.cut(base2, R2)
            if cut2 is None:
                q_dot = np.zeros(5)
            else:
                a2, b2, th2 = cut2.a, cut2.b, cut2.theta
                # the same ellipse may come back with its axes swapped or θ + π
                if abs(a2 - cut.a) + abs(b2 - cut.b) > abs(b2 - cut.a) + abs(a2 - cut.b):
                    a2, b2, th2 = b2, a2, th2 + np.pi / 2
                d_th = (th2 - cut.theta + np.pi / 2) % np.pi - np.pi / 2
                q_dot = np.array([cut2.center[0] - cut.center[0], cut2.center[1] - cut.center[1],
                                  d_th, a2 - cut.a, b2 - cut.b]) / dt
            return q_dot, surface_velocity(p_f)[:2]

        return kin

    @staticmethod
    def left(state: FingerState) -> tuple[np.ndarray, np.ndarray | None]:
        """The mirror finger's force and point on the left drum."""
        m = np.array([1.0, -1.0, 1.0])
        return state.force * m, None if state.point is None else state.point * m

