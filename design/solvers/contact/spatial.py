"""A spatial rod finger against an ellipsoid: the continuation solver.

The same strategy as the planar solver (:mod:`design.solvers.contact.robust`):
never start Newton from a guess that cannot be justified.

1. If the straight finger misses the object, there is no contact.
2. Otherwise the object is moved back, perpendicular to the finger, along
   the direction that needs the smallest shift, until the straight finger
   just grazes it: there the solution is known (no load, straight rod,
   contact at the grazing point). The object is then moved forward to its
   place in steps that halve on failure and double on success.
3. After every step the mode is checked: a contact point past the tip
   becomes tip contact, a tip whose rod turns tangent becomes interior
   contact, a normal force that would pull is a release, a contact at the
   base leaves the model.
4. Along a sequence of poses (time steps) each continues from the last:
   first in one Newton step to the new pose and friction together (the
   usual short step), else geometry then friction in adaptive steps.

Friction enters as a :class:`FrictionLaw`: a given vector (the friction
force per unit normal force, on the finger) and/or regularised Coulomb
friction against the finger's sliding, solved together with the contact.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Callable

import numpy as np

from design.physics.beam import Finger
from design.solvers.beam.collocation import adapted_widths
from design.physics.beam import PointLoad, straight_solution
from design.solvers.beam.rod import RodStiffness
from design.solvers.contact.robust import (BASE_FRACTION, BASE_REACHED, MAX_STEP_ITERATIONS,
                                         PENETRATION_TOL, follow)
from design.solvers.contact.spatial_equations import MODES, spatial_transcription
from design.solvers.buffers import Buffered, evaluate
from design.solvers.compiled import compiled_once
from design.solvers.newton import LU, implicit_rate

#: the straight finger is not inside the object at its deepest point (it
#: touches it at most): a touch without force, not a failure
GRAZES = "the straight finger only grazes the object"
#: residual (dimensionless) below which a Newton solve counts as converged
RESIDUAL_TOL = 1e-8
#: chord iterations a continued solve may take before Newton takes over (a
#: simulation's step converges in 3-10; more means the Jacobian has changed)
CHORD_ITERATIONS = 12


@dataclass(frozen=True)
class Quadric:
    """The object in the finger frame: (r - c)ᵀ Q (r - c) = 1 (m, 1/m²)."""

    center: np.ndarray
    matrix: np.ndarray

    def level(self, pts: np.ndarray) -> np.ndarray:
        """< 0 inside; pts (3, n)."""
        d = pts - self.center[:, None]
        return np.einsum("in,ij,jn->n", d, self.matrix, d) - 1.0

    @property
    def base_level(self) -> float:
        """The level at the frame's origin, the finger's base (< 0: inside)."""
        c = self.center
        return float(c @ self.matrix @ c) - 1.0

    def normal(self, p: np.ndarray) -> np.ndarray:
        g = self.matrix @ (p - self.center)
        return g / np.linalg.norm(g)

    def shifted(self, d: np.ndarray) -> "Quadric":
        return Quadric(self.center + d, self.matrix)

    @property
    def params(self) -> np.ndarray:
        Q = self.matrix
        return np.concatenate([self.center, Q[0, :3], Q[1, 1:3], Q[2, 2:3]])

    @staticmethod
    def from_params(p: np.ndarray) -> "Quadric":
        Q = np.array([[p[3], p[4], p[5]], [p[4], p[6], p[7]], [p[5], p[7], p[8]]])
        return Quadric(np.asarray(p[:3], float), Q)


@dataclass(frozen=True)
class FrictionLaw:
    """The friction force on the finger per unit normal force at a contact r
    (finger frame): t0 - µ w / sqrt(|w|² + ε²), w the tangential part of the
    finger's sliding velocity a + B r over the object (m/s; affine in r for
    rigid motions of finger and object). Only t's tangential part acts."""

    given: np.ndarray = field(default_factory=lambda: np.zeros(3))
    mu: float = 0.0
    #: regularisation speed ε (m/s); any positive value when µ = 0
    speed: float = 1.0
    sliding_at_origin: np.ndarray = field(default_factory=lambda: np.zeros(3))
    sliding_gradient: np.ndarray = field(default_factory=lambda: np.zeros((3, 3)))

    @property
    def params(self) -> np.ndarray:
        """[t0 (3), µ, ε, a (3), B (9, row-major)]: design.solvers.contact.spatial_equations."""
        return np.concatenate([np.asarray(self.given, float), [self.mu, self.speed],
                               np.asarray(self.sliding_at_origin, float),
                               np.asarray(self.sliding_gradient, float).ravel()])

    @staticmethod
    def of(friction: "FrictionLaw | np.ndarray") -> "FrictionLaw":
        """A law as is, or a given vector (3,) as the law that always gives it."""
        if isinstance(friction, FrictionLaw):
            return friction
        return FrictionLaw(given=np.asarray(friction, float))


#: no friction (the parameters the continuation starts from)
NO_FRICTION = FrictionLaw().params


@dataclass
class SpatialState:
    """A solved contact: mode, unknowns, and the object and friction law
    parameters (FrictionLaw.params) they solve."""

    mode: str
    z: np.ndarray
    quadric: Quadric
    friction: np.ndarray
    post: np.ndarray
    #: LU factors of the residual's Jacobian at or near z for the chord method:
    #: those its chord solve converged with, or its own (None: not computed)
    lu: LU | None = None


@dataclass(frozen=True)
class SpatialSolution:
    """One finger's quasi-static contact, in the finger frame (m, N).

    ``force`` is on the object; ``normal_force`` N ≥ 0; ``normal`` the
    object's outward unit normal at ``point``; ``shape_points`` (3, n) the
    whole finger. ``out_of_plane`` is |n_z|, the share of the contact normal
    along the finger's stiff axis (0: the planar model's situation).
    """

    contact: bool
    force: np.ndarray
    normal_force: float
    point: np.ndarray | None
    normal: np.ndarray | None
    arc_length: float
    tip_contact: bool
    converged: bool
    message: str = ""
    penetration: float = 0.0
    shape_points: np.ndarray | None = None
    extras: dict = field(default_factory=dict)
    #: the finger's force on the belt (N, finger frame; None: not on the
    #: belt), its normal part, the tip where it acts, and how far the
    #: finger's deepest point lies below the belt (m) (design/solvers/contact/
    #: spatial_belt.py)
    belt_force: np.ndarray | None = None
    belt_normal_force: float = 0.0
    belt_point: np.ndarray | None = None
    below_belt: float = 0.0

    @property
    def out_of_plane(self) -> float:
        return 0.0 if self.normal is None else float(abs(self.normal[2]))


def no_spatial_contact(length: float, message: str, converged: bool = True) -> SpatialSolution:
    pts = np.array([[0.0, length], [0.0, 0.0], [0.0, 0.0]])
    return SpatialSolution(False, np.zeros(3), 0.0, None, None, 0.0, False, converged, message,
                           shape_points=pts)


def deepest_along(quadric: Quadric, length: float) -> float:
    """Where (m from the base) the straight finger (0 ≤ x ≤ l on the x axis)
    goes deepest into the object: level(x e_x) is a parabola in x with its
    minimum at x* = c·Q e_x / Q00, clipped to the finger."""
    Q, c = quadric.matrix, quadric.center
    return float(np.clip((Q[0] @ c) / Q[0, 0], 0.0, length))


def segment_level(quadric: Quadric, length: float) -> float:
    """min over the straight finger (0 ≤ x ≤ l on the x axis) of the level
    function, at its deepest point: < 0 when it passes through the object."""
    return float(quadric.level(np.array([[deepest_along(quadric, length)], [0.0], [0.0]]))[0])


def grazing_shift(quadric: Quadric, length: float, samples: int = 72
                  ) -> tuple[np.ndarray, float] | None:
    """The smallest shift (3,) perpendicular to the finger that moves the object
    clear of the straight finger, and the arc length where it then grazes.

    For a direction v ⊥ e_x the points x e_x + δ v lie in the object for δ in
    [δ1(x), δ2(x)]; moving the object by -δ v clears the finger when δ ≥
    δ2(x) for every x. The direction minimising max_x δ2 is searched on a
    grid of angles and refined by golden sections.
    """
    Q, c = quadric.matrix, quadric.center
    # a grid along the finger and its deepest point: a finger only just inside
    # the object, between two grid points, is inside at that one
    xs = np.sort(np.append(np.linspace(0.0, length, 201), deepest_along(quadric, length)))
    # the finger's points relative to the centre, and their levels: the same for every v
    d = np.stack([xs, np.zeros_like(xs), np.zeros_like(xs)]) - c[:, None]
    c0 = np.einsum("in,ij,jn->n", d, Q, d) - 1.0

    def far_end(beta: float) -> tuple[float, float]:
        v = np.array([0.0, np.cos(beta), np.sin(beta)])
        a = v @ Q @ v
        b = v @ Q @ d
        disc = b * b - a * c0
        ok = disc >= 0
        if not np.any(ok):
            return -np.inf, 0.0
        d2 = np.where(ok, (-b + np.sqrt(np.where(ok, disc, 0.0))) / a, -np.inf)
        k = int(np.argmax(d2))
        return float(d2[k]), float(xs[k])

    betas = np.linspace(0.0, 2 * np.pi, samples, endpoint=False)
    values = [far_end(b)[0] for b in betas]
    k = int(np.argmin(values))
    if not np.isfinite(values[k]) or values[k] <= 0:
        return None
    lo, hi = betas[k] - 2 * np.pi / samples, betas[k] + 2 * np.pi / samples
    g = (np.sqrt(5) - 1) / 2
    for _ in range(40):
        m1, m2 = hi - g * (hi - lo), lo + g * (hi - lo)
        if far_end(m1)[0] < far_end(m2)[0]:
            hi = m2
        else:
            lo = m1
    beta = (lo + hi) / 2
    delta, x = far_end(beta)
    v = np.array([0.0, np.cos(beta), np.sin(beta)])
    return -delta * v, x


#: kinematics(p) -> (rates of the quadric parameters (9,) in the finger
#: frame, the object's material velocity at p relative to the frame (3,))
Kinematics = Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]]


class SpatialContact:
    """Continuation contact solver for a spatial rod finger.

    Parameters
    ----------
    finger : Finger
        Its three rigidity profiles (:class:`~design.physics.beam.Finger`).
    intervals, degree : int
        Rod collocation mesh.
    tolerance : float
        Newton tolerance on the dimensionless residual.
    """

    def __init__(self, finger: Finger, intervals: int = 6, degree: int = 4,
                 tolerance: float = 1e-12, max_steps: int = 400):
        self.finger = finger
        self.stiffness = RodStiffness.of(finger)
        self.tolerance, self.max_steps = tolerance, max_steps
        self.ei_ref = finger.stiffness.compliance_equivalent(finger.length)
        straight = straight_solution(PointLoad(0.0, 0.0, finger.length), "", 3)
        self.widths = adapted_widths(intervals, finger.stiffness, [straight])
        #: the parameters that follow the quadric and friction law (mesh, stiffness)
        self.tail = np.concatenate([self.widths, self.stiffness.params])
        self.tr = {m: spatial_transcription(self.stiffness, intervals, degree, m) for m in MODES}
        #: each mode's post values (and residual size) and shape, compiled, called
        #: through buffers of this solver's own (design/solvers/buffers.py)
        self.post = {m: Buffered(compiled_once(self.tr[m].post)) for m in MODES}
        self.shape = {m: Buffered(compiled_once(self.tr[m].shape)) for m in MODES}
        self.newton_iterations = 0
        #: mode -> the Jacobian factors of the latest root found in it
        self._factors: dict[str, LU] = {}

    # ----------------------------------------------------------------- API
    def solve(self, quadric: Quadric, friction: FrictionLaw | np.ndarray = FrictionLaw(),
              previous: SpatialState | None = None, detail: bool = True,
              level: float | None = None) -> tuple[SpatialSolution, SpatialState | None]:
        """Contact of the finger with ``quadric`` (finger frame) under a
        friction law or a given friction vector (3,), continued from
        ``previous``; ``level``: the straight finger's :func:`segment_level`,
        if known. Returns the solution and the state to continue from."""
        self.newton_iterations = 0
        length = self.finger.length
        friction = FrictionLaw.of(friction).params
        if quadric.base_level <= 0.0:
            return no_spatial_contact(length, "the finger base is inside the object: invalid "
                                              "pose", converged=False), None
        if (segment_level(quadric, length) if level is None else level) >= 0.0:
            return no_spatial_contact(length, "the straight finger misses the object"), None
        # the usual case, a short step: geometry and friction in one solve, by
        # the chord method from the continued solution's Jacobian, else Newton
        state = None
        if previous is not None:
            state = self._chord(previous, quadric, friction) or \
                self._step(previous, quadric, friction)
        held, msg = 1.0, ""
        if not isinstance(state, SpatialState):
            state, held, msg = self._settle(quadric, friction, previous)
            if state is None:
                return no_spatial_contact(length, msg, converged=msg == GRAZES), None
        sol = self._solution(state, msg)
        sol.extras["friction_held"] = held
        return self.detailed(sol, state) if detail else (sol, state)

    def detailed(self, sol: SpatialSolution, state: SpatialState | None
                 ) -> tuple[SpatialSolution, SpatialState | None]:
        """What an accepted instant keeps of a solve without detail: the
        solution with the finger's shape (a finger that passes into the
        object away from the contact is not converged), and the state with
        LU factors to continue from by the chord method, which become its
        mode's latest: those its chord solve converged with, else its own
        Jacobian's, factored now (factoring at every accepted instant cost
        more than the chord iterations it saves). A solve that ended without
        a state (no contact: a graze, a finger that left the bird) has
        nothing to add."""
        if state is None:
            return sol, None
        tr = self.tr[state.mode]
        q = self._params(state.quadric, state.friction)
        post = state.post
        point, arc = post[:3], float(post[4])
        _, r, _ = self.shape[state.mode](state.z, q)
        if arc < self.finger.length:
            rest = np.linspace(0.0, self.finger.length - arc, 6)[1:]
            r = np.hstack([r, point[:, None] + post[13:16, None] * rest[None, :]])
        depth = -np.min(state.quadric.level(r) / (2 * np.sqrt(np.linalg.eigvalsh(
            state.quadric.matrix).max())))
        if depth > PENETRATION_TOL:
            sol = replace(sol, converged=False, penetration=float(depth), message="; ".join(
                m for m in (sol.message, f"the finger passes {depth:.3g} m into the object "
                                         f"away from the contact") if m))
        lu = state.lu if state.lu is not None else tr.chord.factor(state.z, q)
        if lu is not None:
            self._factors[state.mode] = lu
        return replace(sol, shape_points=r), replace(state, lu=lu)

    def _chord(self, previous: SpatialState, quadric: Quadric, friction: np.ndarray
               ) -> SpatialState | None:
        """The contact at the new parameters by the chord method from
        ``previous``, if it has its Jacobian factors and converges within
        CHORD_ITERATIONS with the mode right; else None. It tries the mode's
        latest factors first (the latest Newton's or commit's: nearest the
        states an integrator's trials solve again and again about one
        instant), then ``previous``'s own. Where the root says the contact
        switched between interior and tip, the chord goes on in the other
        mode with that mode's latest factors, as :meth:`_step` goes on with
        Newton (trials about a switch each paid two Newton solves)."""
        if previous.lu is None:
            return None
        q = self._params(quadric, friction)
        mode, z, factors = previous.mode, previous.z, (self._factors.get(previous.mode),
                                                       previous.lu)
        for _ in range(2):
            z, lu = self.tr[mode].chord.solve_first(z, q, factors, self.tolerance,
                                                    CHORD_ITERATIONS)
            if z is None:
                return None
            post = self.post[mode](z, q)[0].ravel()
            verdict = self._check(mode, post)
            if verdict == "ok":
                return SpatialState(mode, z, quadric, friction, post, lu)
            if verdict not in ("tip", "interior"):
                return None
            mode, z = self._switched(verdict, z)
            factors = (self._factors.get(mode),)
        return None

    def _settle(self, quadric: Quadric, friction: np.ndarray, previous: SpatialState | None):
        """The geometry first, continued from ``previous`` under the friction
        it had (else from first touch); then the friction. Returns (state or
        None, the share of the friction change carried, message)."""
        if previous is not None:
            state, msg = self._continue(previous, quadric, previous.friction)
            if state is None and msg != BASE_REACHED:
                state, msg2 = self._from_grazing(quadric, NO_FRICTION)
                msg = f"continued equilibrium lost ({msg}); snapped to the one found from " \
                      f"first touch" if state is not None else msg2
        else:
            state, msg = self._from_grazing(quadric, NO_FRICTION)
        if state is None:
            return None, 0.0, msg
        state, held = self._apply_friction(state, friction)
        if held < 1.0:
            msg = "; ".join(m for m in (msg, f"sticking: the finger carries {held:.0%} of the "
                                             f"sliding friction (no equilibrium beyond)") if m)
        return state, held, msg

    def sliding_velocity(self, state: SpatialState, kin: Kinematics) -> np.ndarray:
        """The finger's material point at the contact relative to the object's
        surface, tangential part (3,, m/s, finger frame).

        The material point moves in the finger frame by dr_L/dt - d1 dL/dt,
        the rates following from the contact equations by the implicit-
        function theorem with the quadric's rates.
        """
        tr = self.tr[state.mode]
        q = self._params(state.quadric, state.friction)
        jz, jq, jtip = evaluate(tr.sensitivity, state.z, q)
        post = state.post
        q_dot, v_object = kin(post[:3])
        z_dot = implicit_rate(jz, -jq @ q_dot)
        rl_dot = jtip @ z_dot
        d1 = post[13:16]
        v = rl_dot[:3] - d1 * rl_dot[3] - v_object
        n = post[7:10]
        return v - (v @ n) * n

    # ------------------------------------------------------- continuation
    def _params(self, quadric: Quadric, friction: np.ndarray) -> np.ndarray:
        return np.concatenate([[self.finger.length, self.ei_ref], quadric.params, friction,
                               self.tail])

    def _apply_friction(self, state: SpatialState, friction: np.ndarray
                        ) -> tuple[SpatialState, float]:
        """Continue ``state`` from its friction law parameters to ``friction``
        (FrictionLaw.params); where the equilibrium ends before (a fold: the
        sliding friction would drag the contact off), stop at the last
        equilibrium. Its law's parameters interpolate the two laws', so for
        Coulomb laws its friction stays below the larger µ: inside the cone,
        the contact sticks there. Returns the state and the fraction of the
        change carried."""
        if np.array_equal(state.friction, friction):
            return state, 1.0
        start = state.friction
        t, step = 0.0, 1.0
        for _ in range(self.max_steps):
            if t >= 1.0 or step < 1e-3:
                break
            t_new = min(1.0, t + step)
            new = self._step(state, state.quadric, start + t_new * (friction - start))
            if isinstance(new, SpatialState):
                state, t, step = new, t_new, min(2 * step, 1.0)
            else:
                step /= 2
        return state, t

    def _from_grazing(self, quadric: Quadric, friction: np.ndarray):
        graze = grazing_shift(quadric, self.finger.length)
        if graze is None:
            return None, GRAZES
        shift, x_g = graze
        length = self.finger.length
        if x_g <= 1e-9 * length:
            return None, "the object reaches the finger at its base: no bending contact"
        start = quadric.shifted(shift)
        rod = self.tr["interior"].rod
        if x_g < length * (1 - 1e-12):
            mode, extra = "interior", [0.0, x_g / length]
        else:
            mode, extra = "tip", [0.0]
        z = np.concatenate([rod.straight(), extra])
        post = self.post[mode](z, self._params(start, friction))[0].ravel()
        state = SpatialState(mode, z, start, friction, post)
        return self._continue(state, quadric, friction)

    def _continue(self, state: SpatialState, target: Quadric, friction: np.ndarray):
        """Continue ``state`` to the target object and friction in adaptive
        steps (:func:`~design.solvers.contact.robust.follow`)."""
        p0 = np.concatenate([state.quadric.params, state.friction])
        p1 = np.concatenate([target.params, friction])

        def step(s: SpatialState, t: float):
            p = p0 + t * (p1 - p0)
            return self._step(s, Quadric.from_params(p[:9]), p[9:])

        return follow(state, step, lambda: segment_level(target, self.finger.length) >= 0.0,
                      self.max_steps)

    def _step(self, state: SpatialState, quadric: Quadric, friction: np.ndarray):
        """Newton at new parameters from ``state``, with mode switches; None on failure."""
        mode, z = state.mode, state.z
        for _ in range(3):
            z_new, ok, post = self._newton(mode, z, quadric, friction)
            if not ok:
                return None
            verdict = self._check(mode, post)
            if verdict == "ok":
                return SpatialState(mode, z_new, quadric, friction, post)
            if verdict in ("release", "base"):
                return verdict
            mode, z = self._switched(verdict, z_new)
        return None

    def _switched(self, mode: str, z: np.ndarray) -> tuple[str, np.ndarray]:
        """A root's unknowns z carried into ``mode`` (tip: the contact's place
        along the finger dropped; interior: it added, at the tip)."""
        nw = self.tr["interior"].rod.n_w
        return (mode, z[:nw + 1]) if mode == "tip" else (mode, np.concatenate([z, [1.0]]))

    def _newton(self, mode, z0, quadric, friction):
        tr = self.tr[mode]
        q = self._params(quadric, friction)
        root = tr.chord.newton(z0, q, self.tolerance, MAX_STEP_ITERATIONS)
        self.newton_iterations += root.iterations
        if not root.converged:
            return root.z, False, None
        post, resid = (v.ravel() for v in self.post[mode](root.z, q))
        ok = bool(np.isfinite(resid[0]) and resid[0] < RESIDUAL_TOL)
        if ok and root.lu is not None:
            self._factors[mode] = root.lu
        return root.z, ok, post

    def _check(self, mode, post) -> str:
        """'ok', 'tip', 'interior', 'release' or 'base' (see the module docstring)."""
        normal_force, arc, along = post[3], post[4], post[6]
        length = self.finger.length
        if normal_force < 0:
            return "release"
        if mode == "interior":
            if arc > length * (1 + 1e-12):
                return "tip"
            return "ok" if arc > BASE_FRACTION * length else "base"
        return "ok" if along <= 0 else "interior"

    # -------------------------------------------------------------- output
    def _solution(self, state: SpatialState, msg: str) -> SpatialSolution:
        """The state as a :class:`SpatialSolution`, without the finger's shape
        (:meth:`detailed` adds it)."""
        post = state.post
        point, normal_force, arc = post[:3], float(post[3]), float(post[4])
        normal, force_on_finger = post[7:10], post[10:13]
        return SpatialSolution(True, -force_on_finger, normal_force, point, normal, arc,
                               state.mode == "tip", True, msg,
                               extras={"mode": state.mode, "friction": post[16:19].copy(),
                                       "z": state.z.copy(),
                                       "iterations": self.newton_iterations})
