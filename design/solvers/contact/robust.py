"""The default contact solver: continuation from first touch, no tuning.

A contact state is the root of :mod:`design.solvers.contact.equations` in one
of two modes (contact inside the span, or at the tip). Newton from a poor
guess is what made the thesis's Algorithm II land on spurious solutions,
so this solver never starts from a guess it cannot justify:

1. If the straight finger misses the object, there is no contact (F = 0):
   an unloaded finger is then an equilibrium and the one continued from
   before contact.
2. Otherwise the object is moved back, away from the finger along y_f,
   until the straight finger just grazes it. There the solution is known
   exactly (F = 0, straight finger, contact at the grazing point). The
   object is then moved forward to its real place in steps that halve on
   failure and double on success: every step starts inside Newton's
   convergence region of the continued solution. That way can carry the
   object over the finger's base; if it fails, the object is instead
   turned about the base until it grazes the finger and turned back (the
   drum's own motion, which keeps its distance from the base). With
   ``sliding: auto`` the other side is tried too.
3. After every step the mode is checked and switched where it no longer
   holds: a contact point that reaches the tip becomes tip contact; a tip
   whose finger turns tangent to the surface becomes interior contact; a
   force that would pull the finger into the object is a release.
4. Along a pass (a sequence of poses) each pose continues from the previous
   one the same way, so the solution followed is the physically continued
   one.

Friction. With ``sliding: push`` or ``pull`` the side is imposed and the
friction on the finger points tipwards, as in the thesis. With ``auto``,
the side is the one from which the object meets the finger, and the
friction opposes the finger's sliding over the surface: the velocity of
the finger's material point at the contact (drum rotation plus the rate
of deflection, by the implicit-function theorem on the contact equations)
minus the object's surface velocity. If both senses contradict their own
sliding velocity, the contact sticks: the friction ratio in (-µ, µ) that
makes the sliding velocity zero is found by bisection.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from functools import cached_property
from typing import Callable

import numpy as np

from design.physics.beam import Finger, PointLoad, straight_solution
from design.physics.contact import (SIDES, ContactSolution, FingerPose, Motion, grazing,
                                    no_contact, segment_overlap, straight_overlap,
                                    swept_grazing, turned)
from design.physics.ellipse import Ellipse, rotation
from design.solvers.beam.collocation import adapted_widths
from design.solvers.contact.equations import MODES, contact_transcription
from design.solvers.buffers import Buffered
from design.solvers.newton import implicit_rate

#: |penetration| below this (m) is rounding, not a second contact
PENETRATION_TOL = 1e-9
#: contact closer to the base than this fraction of the finger is outside the
#: model: the object is pressed against the drum
BASE_FRACTION = 0.01
BASE_REACHED = ("the contact reached the finger's base (within 1% of its length): the object "
                "presses on the drum, outside the finger model")
#: the same, met only on the way in from first touch along y_f: says nothing of the pose
BASE_PASSED = "the contact reached the finger's base on the way (the object passed over it)"
SIDE_NAMES = {side: name for name, side in SIDES.items()}
#: sliding speeds below this (m/s) count as sticking
STICK_SPEED = 1e-7
#: Newton iterations a solve may take (planar and spatial contacts; a start
#: inside the convergence region needs 3-6): a continuation step that needs
#: more started too far from the continued solution, or stalled at a fold, and
#: is halved, so iterating on is wasted
MAX_STEP_ITERATIONS = 12


def follow(state, step: Callable, clear: Callable[[], bool], max_steps: int):
    """Continue a solved contact ``state`` from t = 0 (its own parameters) to
    t = 1 in steps that halve on failure and double on success.
    ``step(state, t)`` solves at t from ``state``: the new state, None on
    failure, ``"base"`` (the contact reached the finger's base) or
    ``"release"`` (the normal force would pull); ``clear()``: whether the
    straight finger is clear of the target, so that a release ends the
    contact. Returns (state, "") or (None, why)."""
    t, h = 0.0, 1.0
    for _ in range(max_steps):
        if t >= 1.0:
            return state, ""
        t_new = min(1.0, t + h)
        new = step(state, t_new)
        if new is None:
            h /= 2
            if h < 1e-7:
                return None, f"continuation stalled at {t:.6f} of the step"
            continue
        if new == "base":
            return None, BASE_REACHED
        if new == "release":
            if clear():
                return None, "released"
            h /= 2
            if h < 1e-7:
                return None, "the normal force would pull the finger into the object"
            continue
        state, t, h = new, t_new, min(2 * h, 1.0)
    return None, f"no convergence in {max_steps} continuation steps"


@dataclass
class _State:
    """A solved contact: mode, unknowns, and the parameters they solve: the
    ``ellipse``, or for a trial (:meth:`RobustContact.continue_trial`) its
    ``conic`` (centre, B), made an ellipse when the state is continued."""

    mode: str
    z: np.ndarray
    ellipse: Ellipse | None
    tau_mu: float
    side: int
    post: np.ndarray | None = None
    conic: tuple[np.ndarray, np.ndarray] | None = None

    def with_ellipse(self) -> "_State":
        return self if self.ellipse is not None else \
            replace(self, ellipse=Ellipse.from_conic(*self.conic))


class RobustContact:
    """Continuation contact solver on the collocated non-uniform beam.

    Parameters
    ----------
    finger : Finger
    friction : float
        Coefficient of friction µ between finger and object (≥ 0).
    intervals, degree : int
        Beam collocation mesh (see :class:`~design.solvers.beam.collocation.Collocation`).
    tolerance : float
        Newton tolerance on the dimensionless residual.
    """

    name = "robust"

    def __init__(self, finger: Finger, friction: float, intervals: int = 10, degree: int = 4,
                 tolerance: float = 1e-12, max_steps: int = 400,
                 reversal_speed: float | None = None):
        self.finger = finger
        self.mu = float(friction)
        self.intervals, self.degree = intervals, degree
        self.tolerance = tolerance
        self.max_steps = max_steps
        #: None: Coulomb friction with exact stick (quasi-static passes). A speed
        #: (m/s): friction always at the edge of sliding (the thesis's
        #: assumption) and reversed only when the finger slides the other way
        #: faster than this (the grasp dynamics, where an exact stick would tie
        #: every finger's contact to the bird's acceleration, and reversing at
        #: every sign change of a lagged sliding speed chatters)
        self.reversal_speed = reversal_speed
        stiff = finger.stiffness
        self.ei_ref = stiff.compliance_equivalent(finger.length)
        straight = straight_solution(PointLoad(0.0, 0.0, finger.length), "", 3)
        self.widths = adapted_widths(intervals, stiff, [straight])
        self.tr = {m: contact_transcription(stiff, intervals, degree, m) for m in MODES}
        self.newton_iterations = 0
        self._last_iterations = 0

    # ----------------------------------------------------------------- API
    def solve(self, pose: FingerPose, ellipse: Ellipse, sliding: str = "auto",
              motion: Motion | None = None) -> ContactSolution:
        """Contact state of the finger at ``pose`` against the world-frame ``ellipse``.

        With ``sliding: auto`` and a motion, friction makes the state depend on
        its history: the motion is played back to the moment of first touch and
        the contact followed from there (every 1° of drum rotation).
        """
        if sliding == "auto" and motion is not None and self.mu > 0:
            history = self._history(pose, ellipse, motion)
            if history:
                sols = self.solve_pass([h[0] for h in history] + [pose],
                                       [h[1] for h in history] + [ellipse], sliding, motion)
                return sols[-1]
        return self._solve(pose, ellipse, sliding, motion, None)[0]

    def _history(self, pose: FingerPose, ellipse: Ellipse, motion: Motion,
                 step: float = np.radians(1.0)) -> list[tuple[FingerPose, Ellipse]]:
        """Earlier poses, from the last one before first touch up to (not
        including) now, following the motion backwards; [] if the object was
        touching for more than half a drum turn or nothing moves."""
        omega = motion.drum_speed
        speed = float(np.hypot(*motion.object_velocity))
        if omega != 0.0:
            dt = step / abs(omega)
        elif speed > 0.0:
            dt = 0.002 * self.finger.length / speed
        else:
            return []
        back = []
        for k in range(1, int(np.pi / step) + 2):
            t = -k * dt
            p = FingerPose(pose.radius, pose.angle - omega * t)
            c = np.asarray(ellipse.center) + np.asarray(motion.object_velocity) * t
            e = Ellipse(ellipse.a, ellipse.b, (float(c[0]), float(c[1])),
                        ellipse.theta + motion.object_spin * t)
            back.append((p, e))
            if segment_overlap(p.view(e), self.finger.length) >= 0.0:
                return back[::-1]
        return []

    def solve_pass(self, poses: list[FingerPose], ellipses: list[Ellipse],
                   sliding: str = "auto", motion: Motion | None = None,
                   progress=None) -> list[ContactSolution]:
        """A sequence of poses, each continued from the previous solution."""
        out, state = [], None
        for i, (pose, ellipse) in enumerate(zip(poses, ellipses)):
            sol, state = self._solve(pose, ellipse, sliding, motion, state)
            out.append(sol)
            if progress and (i + 1) % 50 == 0:
                progress(f"contact pass: {i + 1}/{len(poses)} poses")
        return out

    # ----------------------------------------------------------- one pose
    def _solve(self, pose, ellipse_w, sliding, motion, previous: _State | None):
        kin = None if motion is None else planar_kinematics(pose, ellipse_w, motion)
        return self.solve_frame(pose.view(ellipse_w), sliding, kin, previous, pose)

    def solve_frame(self, ell: Ellipse, sliding: str, kinematics: "Kinematics | None",
                    previous: _State | None, pose: FingerPose = FingerPose(0.0, 0.0),
                    settle: bool = True, detail: bool = True):
        """Solve with the object already in the finger frame (the 3-D grasp's entry).

        ``kinematics(p)`` gives, for a finger-frame point p, the rates of the
        ellipse's parameters (cx, cy, θ, a, b) in the finger frame and the
        object's material velocity at p relative to the finger frame; it
        decides the side and the friction for ``sliding: auto`` (None: the
        thesis's convention). With ``settle`` false the friction ratio is kept
        from ``previous`` (an integrator's trial evaluations within a step);
        with ``detail`` false the finger's shape and the penetration check are
        skipped (force, point and angles only).
        Returns the solution and the state to continue from at the next time
        or pose.
        """
        self.newton_iterations = 0
        length = self.finger.length
        previous = previous and previous.with_ellipse()
        if ell.level(0.0, 0.0) <= 0.0:
            return no_contact(pose, length, "the finger base is inside the object: invalid pose",
                              converged=False), None
        if segment_overlap(ell, length) >= 0.0:
            return no_contact(pose, length, "the straight finger misses the object"), None
        side = self._side(ell, sliding, kinematics, previous)
        # an imposed side is kept; with ``auto`` the other side is the fallback
        sides = (side,) if sliding in SIDES else (side, -side)
        tau_mu = self._initial_tau_mu(sliding, previous, kinematics)
        continued = previous is not None and previous.side == side
        if continued:
            state, msg = self._continue(previous, ell, tau_mu)
            if state is None:
                # the continued equilibrium ended (a fold, or the way between
                # the poses crossed the base): the finger snaps to another one,
                # found afresh from first touch
                continued = False
                state, msg2 = self._from_first_touch(ell, sides, tau_mu)
                msg = f"continued equilibrium lost ({msg}); snapped to the one found from " \
                      f"first touch" if state is not None else msg2
        else:
            state, msg = self._from_first_touch(ell, sides, tau_mu)
        if state is None and sliding in SIDES and msg != BASE_REACHED:
            other, _ = self._from_first_touch(ell, (-side,), tau_mu)
            if other is not None:
                msg = (f"no equilibrium with the finger deflected to {'+-'[side < 0]}y_f "
                       f"({sliding}) found: {msg}. The object meets the finger from the other "
                       f"side here: sliding {SIDE_NAMES[-side]} or auto finds that equilibrium")
        if state is None:
            return no_contact(pose, length, msg, converged=False), None
        settling = sliding == "auto" and kinematics is not None and self.mu > 0 and settle
        sol, state = self._settled(state, msg, pose, kinematics, settling, detail)
        if continued and sol.penetration > 0.0:
            # the continued equilibrium runs into the object elsewhere (a second
            # contact, outside the model): the one found afresh, if it does not
            fresh, _ = self._from_first_touch(ell, sides, tau_mu)
            if fresh is not None:
                again, fresh = self._settled(
                    fresh, "the continued equilibrium passed into the object; snapped to the "
                           "one found from first touch", pose, kinematics, settling, detail)
                if again.penetration == 0.0:
                    return again, fresh
        return sol, state

    @cached_property
    def _conic(self) -> dict:
        """The contact equations with the ellipse as a conic (centre, B): what
        a section gives without an eigen-decomposition."""
        return {m: contact_transcription(self.finger.stiffness, self.intervals, self.degree, m,
                                         "conic") for m in MODES}

    @cached_property
    def _continued(self) -> dict:
        """:meth:`ContactTranscription.continued` per mode, called through this
        contact's own buffers (the function is shared by fingers, the
        buffers are not)."""
        return {m: Buffered(tr.continued(self.tolerance, MAX_STEP_ITERATIONS))
                for m, tr in self._conic.items()}

    @cached_property
    def _sensitivity(self) -> dict:
        """:attr:`ContactTranscription.sensitivity` per mode, through this
        contact's own buffers."""
        return {m: Buffered(tr.sensitivity) for m, tr in self.tr.items()}

    def continue_trial(self, previous: _State, center: np.ndarray, B: np.ndarray):
        """An integrator's trial evaluation: the contact at a new section of the
        object, the conic (u - c)ᵀ B (u - c) = 1 in the finger frame, by one
        Newton solve from ``previous`` (mode, side and friction kept) in one
        compiled call. Returns (solution, state), or None where that is not
        the whole answer (the finger's base inside the object or its straight
        line clear of it, Newton not converged to the tolerance within
        MAX_STEP_ITERATIONS, a mode switch, a release, the finger bent to the
        other side, F < 0): :meth:`solve_frame` then continues in steps."""
        length, mode = self.finger.length, previous.mode
        if center @ B @ center <= 1.0 or straight_overlap(center, B, length) >= 0.0:
            return None
        q = np.concatenate([[length, self.ei_ref, center[0], center[1], B[0, 0], B[0, 1],
                             B[1, 1], previous.tau_mu], self.widths,
                            self.finger.stiffness.params])
        z, post, resid = (v.ravel() for v in self._continued[mode](previous.z, q))
        if not resid[0] <= self.tolerance or post[3] < 0 or previous.side * post[11] <= 0 \
                or self._check(mode, post) != "ok":
            return None
        state = _State(mode, z, None, previous.tau_mu, previous.side, post, (center, B))
        self.newton_iterations = 0
        return self._brief(state, FingerPose(0.0, 0.0), self._friction_label(state.tau_mu), "",
                           True), state

    def _settled(self, state: _State, msg: str, pose: FingerPose, kinematics, settling: bool,
                 detail: bool) -> tuple[ContactSolution, _State | None]:
        """The solution at ``state``, its friction first made consistent with
        the sliding when ``settling``; with the finger's shape when ``detail``."""
        friction, v_slide, settled = self._friction_label(state.tau_mu), None, True
        if settling:
            state, friction, msg2, v_slide, settled = self._settle_friction(state, kinematics)
            msg = "; ".join(m for m in (msg, msg2) if m)
        if state is None:
            return no_contact(pose, self.finger.length, msg, converged=False), None
        sol = self._solution(state, pose, friction, msg, settled) if detail else \
            self._brief(state, pose, friction, msg, settled)
        sol.extras["sliding_velocity"] = v_slide
        return sol, state

    def _side(self, ell, sliding, kinematics, previous) -> int:
        """+1 (push: finger deflected to +y_f) or -1 (pull)."""
        if sliding in SIDES:
            return SIDES[sliding]
        if previous is not None:
            return previous.side
        # the side the finger has to bend less to clear the object: at first
        # touch (a pass, a time step) the overlap is small on that side only;
        # a single pose with a motion is played back to first touch (solve)
        up, down = grazing(ell, self.finger.length, +1), grazing(ell, self.finger.length, -1)
        return 1 if up[0] <= down[0] else -1

    def _initial_tau_mu(self, sliding, previous, kinematics) -> float:
        if self.mu == 0.0:
            return 0.0
        if sliding in SIDES:
            return self.mu          # the thesis's convention: friction on the finger tipwards
        if previous is not None:
            return previous.tau_mu
        return self.mu              # refined by _settle_friction once the contact is solved

    # ------------------------------------------------------- continuation
    def _from_first_touch(self, ell: Ellipse, sides: tuple[int, ...], tau_mu: float):
        """An equilibrium continued from first touch, on the first of ``sides``
        that has one.

        Two ways in, tried in turn on every side: the object moved back along
        y_f until the straight finger grazes it, then forward (the shortest
        way, but it can carry the object over the finger's base, where the
        contact is lost); then the object turned about the base, the drum's
        own motion, which keeps its distance from the base. Only a contact
        that reaches the base on the second way means the object lies at the
        base.
        """
        failures = []
        for way, approach in (("moved in along y_f", self._moved_in),
                              ("turned in about the base", self._turned_in)):
            for side in sides:
                state, msg = approach(ell, side, tau_mu)
                if state is not None:
                    return state, ""
                failures.append((side, way, msg))
        if all(msg == BASE_REACHED for _, way, msg in failures if way.startswith("turned")):
            return None, BASE_REACHED
        return None, "no equilibrium found from first touch: " + "; ".join(
            f"{SIDE_NAMES[side]}, {way}: {msg}" for side, way, msg in failures)

    def _moved_in(self, ell: Ellipse, side: int, tau_mu: float):
        """Move the object back along -side y_f until the straight finger grazes
        it, then forward."""
        graze = grazing(ell, self.finger.length, side)
        if graze is None:
            return None, "the finger cannot reach the object"
        shift, x_g = graze
        if x_g <= 1e-9 * self.finger.length:
            return None, "the object reaches the finger at its base: no bending contact"
        state = self._touching(ell.shifted(0.0, -side * shift), x_g, side, tau_mu)
        state, msg = self._continue(state, ell, tau_mu)
        return state, BASE_PASSED if msg == BASE_REACHED else msg

    def _turned_in(self, ell: Ellipse, side: int, tau_mu: float):
        """Turn the object about the finger's base until the straight finger
        grazes it, then back (:func:`~design.physics.contact.swept_grazing`)."""
        graze = swept_grazing(ell, self.finger.length, side)
        if graze is None:
            return None, "the finger cannot reach the object"
        angle, x_g = graze
        if x_g <= BASE_FRACTION * self.finger.length:
            return None, BASE_REACHED
        state = self._touching(turned(ell, angle), x_g, side, tau_mu)
        return self._follow(state, lambda t: (turned(ell, angle * (1.0 - t)), tau_mu))

    def _touching(self, start: Ellipse, x_g: float, side: int, tau_mu: float) -> _State:
        """The unloaded straight finger touching ``start`` at (x_g, 0)."""
        length = self.finger.length
        if x_g < length * (1 - 1e-12):
            mode, z_extra = "interior", [x_g / length]
            t_c = np.array([1.0, 0.0])
            normal = np.array([0.0, side])
        else:
            mode, z_extra = "tip", []
            g = start.gradient(length, 0.0)
            normal = g / np.hypot(*g)
            t_c = np.array([1.0, 0.0]) - normal[0] * normal
            t_c = t_c / np.hypot(*t_c) if np.hypot(*t_c) > 0 else np.array([1.0, 0.0])
        e = normal + tau_mu * t_c
        alpha = float(np.arctan2(e[1], -e[0]))
        z = np.concatenate([np.zeros(self.tr[mode].beam.n_w), [0.0, alpha], z_extra])
        return _State(mode, z, start, tau_mu, side)

    def _continue(self, state: _State, target: Ellipse, tau_mu: float):
        """Continue ``state`` to the target ellipse and friction along a straight
        line in (cx, cy, θ, a, b, τµ)."""
        src = state.ellipse
        p0 = np.array([src.center[0], src.center[1], src.theta, src.a, src.b, state.tau_mu])
        p1 = np.array([target.center[0], target.center[1],
                       src.theta + _wrap(target.theta - src.theta), target.a, target.b, tau_mu])

        def path(t):
            p = p0 + t * (p1 - p0)
            return Ellipse(p[3], p[4], (p[0], p[1]), p[2]), p[5]
        return self._follow(state, path)

    def _follow(self, state: _State, path: Callable[[float], tuple[Ellipse, float]]):
        """Continue ``state`` along ``path(t)`` = (ellipse, τµ), t from 0 (the
        state's) to 1 (:func:`follow`)."""
        target = path(1.0)[0]
        return follow(state, lambda s, t: self._step(s, *path(t)),
                      lambda: segment_overlap(target, self.finger.length) >= 0.0, self.max_steps)

    def _step(self, state: _State, ell: Ellipse, tau_mu: float):
        """Newton at new parameters from ``state``, with mode switches; None on failure."""
        mode, z = state.mode, state.z
        for _ in range(3):                         # at most: solve, switch, solve
            z_new, ok, post = self._newton(mode, z, ell, tau_mu)
            # a step must converge quickly and stay on its side: a long Newton
            # run, or a finger bent the other way, means the step jumped branch
            if not ok or self._last_iterations > MAX_STEP_ITERATIONS \
                    or state.side * post[11] <= 0:
                return None
            verdict = self._check(mode, post)
            if verdict == "ok":
                return _State(mode, z_new, ell, tau_mu, state.side, post)
            if verdict in ("release", "base"):
                return verdict
            if verdict == "tip":
                mode, z = "tip", z_new[:-1]
            else:                                  # tip turned tangent: contact moves inside
                mode, z = "interior", np.concatenate([z_new, [1.0]])
        return None

    def _newton(self, mode, z0, ell, tau_mu):
        tr = self.tr[mode]
        q = tr.parameters(self.finger.length, self.ei_ref, ell, tau_mu, self.widths,
                          self.finger.stiffness)
        rf = tr.rootfinder(self.tolerance, MAX_STEP_ITERATIONS)
        z = np.asarray(rf(z0, q)).ravel()
        self._last_iterations = int(rf.stats().get("iter_count", 0))
        self.newton_iterations += self._last_iterations
        post, resid = (np.asarray(v).ravel() for v in tr.post(z, q))
        ok = bool(rf.stats().get("success", False)) and np.isfinite(resid[0]) \
            and resid[0] < 1e-8
        if ok and post[3] < 0:                     # F < 0 with α is F > 0 with α + π
            nw = tr.beam.n_w
            z[nw], z[nw + 1] = -z[nw], z[nw + 1] + np.pi
            post, _ = (np.asarray(v).ravel() for v in tr.post(z, q))
        return z, ok, post

    def _check(self, mode, post) -> str:
        """'ok', 'tip' (interior contact passed the tip), 'interior' (tip turned
        tangent), 'release' (the force would pull the finger in) or 'base'
        (the contact reached the finger's base)."""
        length, along, push = post[5], post[7], post[8]
        if post[3] > 0 and push <= 0:
            return "release"
        if mode == "interior":
            if length > self.finger.length * (1 + 1e-12):
                return "tip"
            return "ok" if length > BASE_FRACTION * self.finger.length else "base"
        return "ok" if along <= 0 else "interior"

    # ------------------------------------------------------------ friction
    def _settle_friction(self, state, kin):
        """Friction ratio m = τµ consistent with the sliding velocity v(m).

        Physical states: sliding tipwards with the friction on the finger
        baseward (m = -µ, v ≥ 0), the mirror (m = +µ, v ≤ 0), or sticking
        (|m| < µ, v = 0). From the current m the ratio moves in the direction
        that opposes the sliding, and stops where v vanishes (stick) or at
        the bound (sliding the other way): the friction force is continued,
        never flipped past a sticking state.

        Returns the state, its friction label, a message, the sliding
        velocity (m/s) and whether the friction was settled; where it was not
        (no equilibrium with the friction it needs, or a stick the bisection
        could not pin down) the message says why and the state is the last
        one reached.
        """
        v = self._sliding_velocity(state, kin)
        if self.reversal_speed is not None:
            if self._margin(v, state.tau_mu) >= 0.0:             # not clearly reversed
                return state, self._friction_label(state.tau_mu), "", v, True
            moved, msg = self._refriction(state, -state.tau_mu)
            if moved is None:
                return (state, self._friction_label(state.tau_mu),
                        f"the friction could not reverse ({msg}): the finger slides at "
                        f"{v:+.3g} m/s against it", v, False)
            return moved, self._friction_label(moved.tau_mu), "", v, True
        if self._consistent(state.tau_mu, v):
            return state, self._friction_label(state.tau_mu), "", v, True
        target = -self.mu if v > 0 else self.mu
        end, msg = self._refriction(state, target)
        if end is None:
            return None, "none", f"no equilibrium with friction ratio {target:+g}: {msg}", None, \
                False
        v_end = self._sliding_velocity(end, kin)
        if v_end * v > 0 or v_end == 0.0:          # still sliding the same way: at the bound
            return end, self._friction_label(end.tau_mu), "", v_end, True
        a, b, v_a = state, end, v                   # v changes sign in between: stick
        settled, why = False, "60 halvings"
        for _ in range(60):
            mid, msg = self._continue(a, a.ellipse, 0.5 * (a.tau_mu + b.tau_mu))
            if mid is None:
                why = msg
                break
            v_mid = self._sliding_velocity(mid, kin)
            if v_mid * v_a > 0:
                a, v_a = mid, v_mid
            else:
                b = mid
            if abs(v_a) <= STICK_SPEED or abs(b.tau_mu - a.tau_mu) < 1e-12 * self.mu:
                settled = True
                break
        if not settled:
            return (a, "stick", f"sticking contact not resolved: the friction ratio is between "
                                f"{a.tau_mu:+.4f} and {b.tau_mu:+.4f} (µ = {self.mu:g}), where "
                                f"the finger still slides at {v_a:+.3g} m/s ({why})", v_a, False)
        return (a, "stick", f"sticking contact: friction ratio {a.tau_mu:+.4f} (µ = {self.mu:g})",
                v_a, True)

    def reversal_margin(self, state: _State, kin: "Kinematics") -> float:
        """With the friction kept at the edge of sliding (``reversal_speed``
        set): how far the contact ``state`` is from having its friction
        reversed, reversal_speed µ - v τµ (m/s times µ; v the sliding
        velocity). Below zero the finger slides against its friction faster
        than the reversal speed, and the next settled solve reverses it."""
        return self._margin(self._sliding_velocity(state.with_ellipse(), kin), state.tau_mu)

    def _margin(self, v: float, tau_mu: float) -> float:
        return self.reversal_speed * self.mu - v * tau_mu

    def _refriction(self, state: _State, tau_mu: float):
        """``state`` with its friction ratio continued to ``tau_mu``; where that
        equilibrium ends first (a fold), the one found afresh from first touch."""
        end, msg = self._continue(state, state.ellipse, tau_mu)
        if end is not None:
            return end, ""
        end, msg2 = self._from_first_touch(state.ellipse, (state.side,), tau_mu)
        return end, "" if end is not None else f"{msg}; from first touch: {msg2}"

    def _consistent(self, tau_mu: float, v: float) -> bool:
        if tau_mu >= self.mu * (1 - 1e-12):
            return v <= 0
        if tau_mu <= -self.mu * (1 - 1e-12):
            return v >= 0
        return abs(v) <= STICK_SPEED

    def _sliding_velocity(self, state: _State, kin: "Kinematics") -> float:
        """Finger material point's velocity relative to the object's surface,
        along the sliding tangent (m/s, + towards the finger tip).

        The finger's material point at the contact moves in its own frame by
        d(x_L, y_L)/dt - t_f dL/dt, the rates following from the contact
        equations by the implicit-function theorem with the ellipse's
        parameter rates; the object's point moves relative to the frame as
        ``kin`` says.
        """
        tr = self.tr[state.mode]
        q = tr.parameters(self.finger.length, self.ei_ref, state.ellipse, state.tau_mu,
                          self.widths, self.finger.stiffness)
        jz, jq, jtip, post = self._sensitivity[state.mode](state.z, q)
        post = post.ravel()
        point = post[:2]
        q_dot, v_object = kin(point)
        z_dot = implicit_rate(jz, -jq @ q_dot)
        x_dot, y_dot, l_dot = jtip @ z_dot
        t_f = np.array([np.cos(post[2]), np.sin(post[2])])
        v_material = np.array([x_dot, y_dot]) - t_f * l_dot
        return float((v_material - v_object) @ post[9:11])

    def _friction_label(self, tau_mu: float) -> str:
        if self.mu == 0.0 or tau_mu == 0.0:
            return "none"
        return "tipward" if tau_mu > 0 else "baseward"

    # -------------------------------------------------------------- output
    def _solution(self, state: _State, pose: FingerPose, friction: str, msg: str,
                  settled: bool) -> ContactSolution:
        """The contact with the finger's whole shape; converged when the
        friction settled and the finger stays out of the object elsewhere."""
        tr = self.tr[state.mode]
        q = tr.parameters(self.finger.length, self.ei_ref, state.ellipse, state.tau_mu,
                          self.widths, self.finger.stiffness)
        post, resid = (np.asarray(v).ravel() for v in tr.post(state.z, q))
        s, x, y, psi, moment = (np.asarray(v).ravel() for v in tr.shape(state.z, q))
        x_l, y_l, psi_l, force, alpha, arc = post[:6]
        length = self.finger.length
        if arc < length:                           # the straight rest of the finger
            rest = np.linspace(arc, length, 6)[1:]
            s = np.concatenate([s, rest])
            x = np.concatenate([x, x_l + (rest - arc) * np.cos(psi_l)])
            y = np.concatenate([y, y_l + (rest - arc) * np.sin(psi_l)])
        # the finger must not pass through the object anywhere but at the contact
        depth = -np.min(state.ellipse.distance_outside(x, y))
        penetration = float(max(depth, 0.0)) if depth > PENETRATION_TOL else 0.0
        converged = settled and penetration == 0.0
        if penetration > 0.0:
            msg = "; ".join(m for m in (msg, f"the finger passes {penetration:.3g} m into the "
                                             f"object away from the contact") if m)
        return ContactSolution(
            True, float(force), float(alpha), float(arc), (float(x_l), float(y_l)),
            float(psi_l), state.mode == "tip", "push" if state.side > 0 else "pull", friction,
            pose, s, x, y, converged, self.newton_iterations, msg, penetration,
            extras={"residual": float(resid[0]), "friction_ratio": state.tau_mu,
                    "mode": state.mode, "base_moment": float(moment[0]), "z": state.z.copy()})

    def _brief(self, state: _State, pose: FingerPose, friction: str, msg: str, settled: bool
               ) -> ContactSolution:
        """The contact without the finger's shape (for trial evaluations):
        penetration not checked (nan); converged when the friction settled."""
        x_l, y_l, psi_l, force, alpha, arc = state.post[:6]
        s = np.array([0.0, arc])
        return ContactSolution(
            True, float(force), float(alpha), float(arc), (float(x_l), float(y_l)),
            float(psi_l), state.mode == "tip", "push" if state.side > 0 else "pull", friction,
            pose, s, np.array([0.0, x_l]), np.array([0.0, y_l]), settled,
            self.newton_iterations, msg, float("nan"),
            extras={"friction_ratio": state.tau_mu, "mode": state.mode, "z": state.z.copy()})


def _wrap(angle: float) -> float:
    return float((angle + np.pi) % (2 * np.pi) - np.pi)


#: kinematics(p_f) -> (rates of (cx, cy, θ, a, b) in the finger frame, the
#: object's material velocity at p_f relative to the finger frame), m/s
Kinematics = Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]]


def planar_kinematics(pose: FingerPose, ellipse_w: Ellipse, motion: Motion) -> Kinematics:
    """Rates seen from a finger on a drum turning at ω (clockwise for ω > 0)
    with the object translating and spinning in the plane."""
    omega = motion.drum_speed
    rot = rotation(pose.angle)
    c_w = np.asarray(ellipse_w.center, float)
    v_obj = np.asarray(motion.object_velocity, float)
    J = np.array([[0.0, -1.0], [1.0, 0.0]])
    c_dot = omega * J @ rot.T @ c_w + rot.T @ v_obj
    q_dot = np.array([c_dot[0], c_dot[1], motion.object_spin + omega, 0.0, 0.0])

    def kin(p_f: np.ndarray):
        p_w = pose.to_world(p_f[0], p_f[1])[:, 0]
        frame_v = omega * np.array([p_w[1], -p_w[0]])        # the drum carries the frame
        r = p_w - c_w
        object_v = v_obj + motion.object_spin * np.array([-r[1], r[0]])
        return q_dot, rot.T @ (object_v - frame_v)

    return kin
