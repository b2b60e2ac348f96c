"""A finger against the bird and the belt: continuation with contact events.

What both finger models share (design/solvers/contact/spatial_belt.py for the
rod, planar_belt.py for the thesis's planar finger). A finger that can reach
the belt is solved here; every other finger by its model's bird-only solver.
The finger's state is one of six modes: ``free`` (straight, unloaded), the
bird-only ``interior`` and ``tip``, and the belt modes ``belt``,
``tip+belt`` and ``interior+belt``.

From a solved state the bird, the belt and both friction laws are moved to
their new values in one step; where Newton cannot take it, in steps that
halve on failure and double on success (first the geometry under the old
laws, then the laws, as the bird-only solvers do); where a contact starts
inside it, along its own path to where the contact starts and on in one
step from there. Each solve is the chord method with the latest Jacobian
factors of its mode, Newton where that does not converge (a mode's first
solve after a switch no longer pays for a Newton solve and a
factorisation). After every step the contacts are checked:

* a contact whose normal force would pull lets go;
* the tip passing below the belt, or the finger entering the bird, starts a
  contact;
* the bird's contact point reaching the tip, or the tip turning tangent to
  the bird, switches between interior and tip contact.

A contact starts where it should, not a step late: the step is shortened
until the crossing is within :data:`EVENT_DEPTH` (or the step within
:data:`EVENT_STEP`), the mode is switched there and the solve repeated in
the new mode. When the continued state cannot be followed (a fold), the
finger is solved afresh from the straight finger, with the bird and the
belt brought in from first touch.

A point of the finger below the belt other than the tip (the finger lying
on it) is outside the model: it is reported, not corrected.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import NamedTuple

import numpy as np

from design.solvers.buffers import Buffered
from design.solvers.compiled import compiled_once
from design.solvers.contact.robust import BASE_FRACTION, BASE_REACHED, MAX_STEP_ITERATIONS
from design.solvers.contact.spatial import CHORD_ITERATIONS
from design.solvers.newton import LU

#: a contact event is located to within this penetration (m) ...
EVENT_DEPTH = 1e-8
#: ... or this fraction of the continuation step
EVENT_STEP = 1e-6
#: a first touch of the bird found in one mode's discretisation may pull in the
#: contact mode's, which puts the surface a few micrometres elsewhere: the
#: finger then grazes the bird, without force, until it is this far (m) inside
GRAZE_DEPTH = 2e-5


class Pace(NamedTuple):
    """How a path cuts a step Newton cannot take (to 1/``shrink`` of it),
    and where it gives up: a path whose steps must be shorter than ``stall``
    of it to converge has lost its equilibrium (a fold), and the state is
    then found afresh."""

    stall: float
    shrink: float


#: the accepted instant's pace: halving, a fold located to 1e-7 of the path
COMMIT = Pace(1e-7, 2.0)
#: an integrator's trial, continued from the accepted state, takes its step
#: whole: where Newton cannot take it, its equilibrium counts as lost (found
#: afresh). It only has to tell that its step crosses a fold: its instant, if
#: accepted, is solved again at COMMIT's pace, and a step too long for Newton
#: is the integrator's to shorten, which it does when the force found afresh
#: makes it reject the step. (Cutting the step to 1/16, down to 1e-3 of it,
#: cost each trial past a fold about ten failed Newton solves, and an
#: integrator retries a step across a fold many times.)
TRIAL = Pace(1.0, 2.0)
#: the finger's modes that touch the bird, and those that touch the belt
BIRD_MODES = ("interior", "tip", "tip+belt", "interior+belt")
BELT_MODES = ("belt", "tip+belt", "interior+belt")


class Deepest(NamedTuple):
    """Where a finger's centreline goes deepest into the bird: the bird's
    level (r - c)ᵀ M (r - c) - 1 there (< 0 inside), the place as a fraction
    of the centreline's length, the point (m) and its unit tangent."""

    level: float
    fraction: float
    point: np.ndarray
    tangent: np.ndarray


#: where :func:`deepest` first looks along each gap between a finger's points
GAP_GRID = np.linspace(0.0, 1.0, 33)
#: the powers 0 to 6 of :data:`GAP_GRID` (7, 33): a degree-6 polynomial's
#: values there are its coefficients times these
GAP_POWERS = GAP_GRID[None, :] ** np.arange(7)[:, None]


def deepest(points: np.ndarray, tangents: np.ndarray, center: np.ndarray,
            matrix: np.ndarray) -> Deepest:
    """The bird's (centre c, matrix M) lowest level along the finger's
    centreline, not only at its points: the curve through ``points`` (dim,
    n; m, base to tip) with unit ``tangents`` (dim, n) there, each gap a
    cubic Hermite arc, its level a degree-6 polynomial in the gap's
    parameter, minimised on :data:`GAP_GRID` and polished by Newton's
    method inside the grid cells about the least value (a polynomial's
    roots are inaccurate when its top coefficients are round-off, as on a
    straight gap). Where the least value is at a point the finger's curve
    passes, both gaps that meet there are polished and the lower taken: the
    two gaps' values there differ by round-off alone. Between the points a
    convex bird can cross the chord unseen."""
    rel = points - center[:, None]
    chords = np.linalg.norm(np.diff(points, axis=1), axis=0)
    p0, p1 = rel[:, :-1], rel[:, 1:]
    m0, m1 = chords * tangents[:, :-1], chords * tangents[:, 1:]
    # r(s) - c = Σ_i a_i s^i over each gap, s in [0, 1]; the level is Σ_ij a_iᵀ M a_j s^(i+j) - 1
    a = np.stack([p0, m0, 3 * (p1 - p0) - 2 * m0 - m1, 2 * (p0 - p1) + m0 + m1])
    per_gap = a.transpose(2, 0, 1)                                # (gaps, 4, dim)
    gram = per_gap @ matrix @ per_gap.transpose(0, 2, 1)          # a_iᵀ M a_j
    coef = np.zeros((chords.size, 7))
    for i in range(4):
        coef[:, i:i + 4] += gram[:, i]
    coef[:, 0] -= 1.0
    values = coef @ GAP_POWERS
    k, j = np.unravel_index(int(np.argmin(values)), values.shape)
    last = GAP_GRID.size - 1
    cells = [(k, j)] + ([(k - 1, last)] if j == 0 and k > 0 else []) + \
        ([(k + 1, 0)] if j == last and k + 1 < chords.size else [])
    (level, u), k = min((_polished(coef[g], values[g, c], c), g) for g, c in cells)
    tangent = np.tensordot(np.arange(4) * np.concatenate([[0.0], u ** np.arange(3)]),
                           a[:, :, k], axes=1)
    return Deepest(level, float((chords[:k].sum() + chords[k] * u) / chords.sum()),
                   center + np.tensordot(u ** np.arange(4), a[:, :, k], axes=1),
                   tangent / np.linalg.norm(tangent))


def _polished(coef: np.ndarray, value: float, j: int) -> tuple[float, float]:
    """A gap's level polynomial (coefficients, degree 6) minimised by
    Newton's method from grid point j (its value there ``value``) within the
    cells beside it: (the least level found, its parameter u)."""
    level = coef.tolist()
    slope = [i * c for i, c in enumerate(level)][1:]
    curvature = [i * c for i, c in enumerate(slope)][1:]
    lo, hi = GAP_GRID[max(j - 1, 0)], GAP_GRID[min(j + 1, GAP_GRID.size - 1)]
    u = float(GAP_GRID[j])
    for _ in range(20):
        bend = horner(curvature, u)
        if bend <= 0.0:
            break
        step = float(np.clip(u - horner(slope, u) / bend, lo, hi))
        done, u = step == u, step
        if done:
            break
    found = horner(level, u)
    return (found, u) if found <= value else (value, float(GAP_GRID[j]))


def horner(coef: list[float], u: float) -> float:
    """Σ_i coef_i u^i by Horner's rule, as numpy's polyval evaluates it."""
    value = coef[-1]
    for c in coef[-2::-1]:
        value = c + value * u
    return value


@dataclass(frozen=True)
class Plane:
    """The belt in a finger frame: n·r = e, n its upward unit normal (3,
    spatial; (2,) in the planar finger's bending plane), e in m."""

    normal: np.ndarray
    offset: float

    def level(self, pts: np.ndarray) -> np.ndarray:
        """Height above the belt (m) of points (dim, n); < 0 below it."""
        return self.normal @ pts - self.offset

    @property
    def params(self) -> np.ndarray:
        return np.concatenate([self.normal, [self.offset]])

    @staticmethod
    def from_params(p: np.ndarray) -> "Plane":
        n = np.asarray(p[:-1], float)
        size = np.linalg.norm(n)
        return Plane(n / size, float(p[-1]) / size)

    def lowered_to(self, point: np.ndarray) -> "Plane":
        """The same plane moved down, if need be, to just below ``point``."""
        return Plane(self.normal, min(self.offset, float(self.normal @ point) - EVENT_DEPTH))


@dataclass(frozen=True)
class Belted:
    """A finger's state against the bird and the belt: mode, unknowns (None
    when ``free``), the bird's parameters in the model's form (None: out of
    reach) and its friction's, the belt and its friction law's parameters,
    and the post values (the model's belt layout; None when ``free``)."""

    mode: str
    z: np.ndarray | None
    bird: np.ndarray | None
    friction: np.ndarray
    plane: Plane
    belt: np.ndarray
    post: np.ndarray | None = None
    #: the share of the last friction change carried (below 1: sticking)
    held: float = 1.0
    #: planar: the side the bird bends the finger to (+1: towards +y)
    side: int = 0
    #: the LU factors of the mode's residual Jacobian near z (for the chord
    #: method; None: not computed)
    lu: LU | None = None
    #: how far (m) the finger may enter the bird before a contact is tried
    #: (GRAZE_DEPTH after a first touch that would pull, else 0)
    graze: float = 0.0


class BeltedContact:
    """The continuation of :class:`Belted` states; a finger model supplies the
    equations and the geometry (the methods that raise NotImplementedError).

    Attributes
    ----------
    length : float
        The finger's length (m).
    n_bird : int
        The size of the bird's parameters.
    max_steps : int
    """

    length: float
    n_bird: int
    max_steps: int = 400

    def __init__(self):
        #: Newton solves of the last :meth:`continued`; Newton's method's calls
        #: of every call (where the chord method did not converge: the costly ones)
        self.newton_iterations = self.newton_total = 0
        #: whether the last :meth:`continued` lost the continued equilibrium
        self.lost = False
        self._calls: dict = {}
        #: mode -> the Jacobian factors of the latest root found in it
        self._factors: dict = {}

    def continued(self, target: Belted, previous: Belted | None, pace: Pace = COMMIT
                  ) -> tuple[Belted | None, str]:
        """The state at ``target``'s bird, belt and laws, continued from
        ``previous`` (its mode and unknowns are ignored; lost where its path
        stalls at ``pace``), else afresh; the message says what happened on
        the way."""
        self.newton_iterations = 0
        self.lost = False
        state, msg = None, ""
        if previous is not None and (target.bird is not None or previous.bird is None):
            state, msg = self._follow(previous, target, pace)
        if state is not None:
            return state, msg
        fresh, msg2 = self._follow(self.free(target), target)
        if fresh is None:
            return None, msg2 if not msg else f"{msg}; afresh: {msg2}"
        if previous is not None and msg:
            self.lost = True
            msg = f"continued equilibrium lost ({msg}); snapped to the one found from " \
                  f"first touch"
        return fresh, msg

    def clearance(self, state: Belted, target: Belted) -> float | None:
        """How far (m) the finger of ``state`` (``free`` or ``belt``: not
        touching the bird) is clear of ``target``'s bird, solved in its own
        mode at ``target``'s belt and belt law (< 0: inside, where a
        continuation to ``target`` would start the contact; None: not solved
        in one step)."""
        new = self._newton(replace(state, bird=target.bird, plane=target.plane,
                                   belt=target.belt))
        return None if new is None else -self.excess(new, "bird")

    def lowered(self, state: Belted) -> Belted:
        """A solved bird-only state (mode, z, bird, friction, belt) with the
        belt lowered to its tip: the belt then comes in from first touch."""
        post = self.calls(state.mode)[0](state.z, self.q(state))[0].ravel()
        solved = self.solved(state, post)
        plane = state.plane.lowered_to(self.tip(solved))
        return self.solved(replace(solved, plane=plane), post)

    # ------------------------------------------------------- continuation
    def _params(self, state: Belted) -> np.ndarray:
        bird = np.zeros(self.n_bird) if state.bird is None else state.bird
        return np.concatenate([bird, state.friction, state.plane.params, state.belt])

    def _moved(self, state: Belted, p: np.ndarray) -> Belted:
        nb, nf, nd = self.n_bird, state.friction.size, state.plane.params.size
        bird = None if state.bird is None else p[:nb]
        return replace(state, bird=bird, friction=p[nb:nb + nf],
                       plane=Plane.from_params(p[nb + nf:nb + nf + nd]), belt=p[nb + nf + nd:])

    def _follow(self, state: Belted, target: Belted, pace: Pace = COMMIT
                ) -> tuple[Belted | None, str]:
        """Continue ``state`` to ``target``: the usual short step, geometry and
        friction in one solve; else the geometry under the state's own
        friction (lost where it stalls at ``pace``), then the
        friction (where the equilibrium ends before, a fold, the contact
        sticks at the last one: ``held`` < 1)."""
        if state.bird is None and target.bird is not None:
            state = replace(state, bird=target.bird)
        whole = replace(state, bird=target.bird, plane=target.plane, friction=target.friction,
                        belt=target.belt)
        new = self._step(state, whole, 1.0)
        if isinstance(new, Belted):
            return replace(new, held=1.0), ""
        if isinstance(new, tuple):
            # a contact starts inside the step: located on the whole step's path
            # (the two stages below are for a step Newton cannot take)
            located, _ = self._path(state, self._params(whole), exact=True,
                                    h=self._to_event(state, new, 1.0), pace=pace)
            if located is not None:
                return located, ""
        geometry = replace(state, bird=target.bird, plane=target.plane)
        state, msg = self._path(state, self._params(geometry), exact=True, pace=pace)
        if state is None:
            return None, msg
        laws = replace(state, friction=target.friction, belt=target.belt)
        return self._path(state, self._params(laws), exact=False)

    def _path(self, state: Belted, end: np.ndarray, exact: bool, h: float = 1.0,
              pace: Pace = COMMIT) -> tuple[Belted | None, str]:
        """From ``state`` to the parameters ``end`` in adaptive steps (the
        first ``h`` of the way), with contact events, a step Newton cannot
        take cut and the path stalled at ``pace``. ``exact`` false: stop at the last
        equilibrium before a fold (``held`` the share carried)."""
        start = self._params(state)
        if np.array_equal(start, end):
            return state, ""
        t = 0.0
        for _ in range(self.max_steps):
            if t >= 1.0:
                return replace(state, held=1.0), ""
            t_new = min(1.0, t + h)
            new = self._step(state, self._moved(state, start + t_new * (end - start)), h)
            if isinstance(new, Belted):
                # past a located event the short step was the event's, not the
                # path's: the rest is tried at once, as the first step was
                grow = 1.0 if new.mode != state.mode else 2 * h
                state, t, h = new, t_new, min(grow, 1.0)
                continue
            if new == "base":
                return None, BASE_REACHED
            if isinstance(new, tuple):
                h = self._to_event(state, new, h)
                continue
            h /= pace.shrink
            if h < pace.stall:
                if exact:
                    return None, f"continuation stalled at {t:.6f} of the step"
                return replace(state, held=t), ""
        return None, f"no convergence in {self.max_steps} continuation steps"

    def _to_event(self, state: Belted, located: tuple, h: float) -> float:
        """A step of h from ``state`` at whose end a contact has started
        (``located``: ("locate", kind, depth), ``depth`` m deep there),
        shortened to just past the crossing: where the depth, near linear in
        the step, passes EVENT_DEPTH / 2 (a secant from the clearance now)."""
        _, kind, depth = located
        before = self.excess(state, kind)
        return h * ((-before + EVENT_DEPTH / 2) / (depth - before) if before < 0.0 else 0.5)

    def _step(self, state: Belted, at: Belted, h: float):
        """Solve at the parameters of ``at`` from ``state`` (a step of relative
        size h): the new state; None (shorten the step: Newton failed);
        ("locate", kind, depth) (a contact starts inside it, ``depth`` m deep
        at its end: shorten it to where it starts); ``base``."""
        mode, z = state.mode, state.z
        touched = None
        for _ in range(4):
            new = self._newton(replace(at, mode=mode, z=z))
            if new is None:
                return None
            if new.graze > 0.0 and self.depth(new, "bird") < 0.0:
                new = replace(new, graze=0.0)              # clear of the bird again
            event = self.event(new)
            if event is None:
                return new
            kind, depth = event
            if kind == "base":
                return "base"
            if kind == "release-bird" and touched is not None:
                # a first touch that pulls grazes; one that pulls again has no
                # contact to follow here
                return replace(touched, graze=GRAZE_DEPTH) if touched.graze == 0.0 else None
            if depth > EVENT_DEPTH and h > EVENT_STEP and kind in ("bird", "belt"):
                return "locate", kind, depth
            switched = self.switch(new, kind)
            if switched is None:
                return None
            touched = new if kind == "bird" else None
            mode, z = switched.mode, switched.z
            at = replace(at, side=switched.side, lu=None)
        return None

    def _newton(self, state: Belted) -> Belted | None:
        """Newton in the state's mode at its parameters from its z; None when
        it does not converge within MAX_STEP_ITERATIONS. The chord method
        goes first, with its mode's latest Jacobian factors (the latest
        Newton's or :meth:`with_lu`'s: nearest the states an integrator's
        trials solve again and again about one instant), then with the
        state's own; where Newton takes over, the factors of its last
        iteration become the mode's latest. The state solved carries the
        factors it was solved with."""
        if state.mode == "free":
            return state
        post = self.calls(state.mode)[0]
        q = self.q(state)
        chord = self.transcription(state.mode).chord
        z, lu = chord.solve_first(state.z, q, (self._factors.get(state.mode), state.lu),
                                  self.tolerance, CHORD_ITERATIONS)
        newton = z is None
        if newton:
            self.newton_total += 1
            root = chord.newton(state.z, q, self.tolerance, MAX_STEP_ITERATIONS)
            if not root.converged:
                return None
            z, lu = root.z, root.lu or chord.factor(root.z, q)
        self.newton_iterations += 1
        post, resid = (v.ravel() for v in post(z, q))
        if not (np.isfinite(resid[0]) and resid[0] < 1e-8):
            return None
        if newton:
            self._factors[state.mode] = lu
        return self.solved(replace(state, z=z, lu=lu), post)

    def with_lu(self, state: Belted) -> Belted:
        """The state with its Jacobian's LU factors, factored at its unknowns,
        for continuing by the chord method; they become its mode's latest.
        (Keeping the factors it was solved with instead, as the bird-only
        solver does, made the belt continuations call Newton's method five
        to seven times as often on Table 5-5's birds.)"""
        if state.mode == "free":
            return state
        lu = self.transcription(state.mode).chord.factor(state.z, self.q(state))
        if lu is not None:
            self._factors[state.mode] = lu
        return replace(state, lu=lu)

    def calls(self, mode: str) -> tuple[Buffered, Buffered]:
        """A mode's post values and the finger's shape, compiled, called
        through buffers (design/solvers/buffers.py)."""
        if mode not in self._calls:
            tr = self.transcription(mode)
            self._calls[mode] = tuple(Buffered(compiled_once(f)) for f in (tr.post, tr.shape))
        return self._calls[mode]

    # --------------------------------------------------------- the model's
    tolerance: float = 1e-12

    def free(self, target: Belted) -> Belted:
        """The straight finger with the bird and the belt moved back to first
        touch (or left where they are if it misses them)."""
        raise NotImplementedError

    def transcription(self, mode: str):
        raise NotImplementedError

    def q(self, state: Belted) -> np.ndarray:
        raise NotImplementedError

    def solved(self, state: Belted, post: np.ndarray) -> Belted | None:
        """A converged Newton solve's state with its post values in the belt
        layout (None: the solve left the branch)."""
        raise NotImplementedError

    def tip(self, state: Belted) -> np.ndarray:
        """The finger's tip in its frame (m)."""
        raise NotImplementedError

    def depth(self, state: Belted, kind: str) -> float:
        """How far (m) the finger is into the belt (``kind`` belt: its tip) or
        the bird (``bird``; the bird out of reach: -inf), < 0 clear of it."""
        raise NotImplementedError

    def excess(self, state: Belted, kind: str) -> float:
        """:meth:`depth` beyond what the state allows before a contact starts."""
        return self.depth(state, kind) - (state.graze if kind == "bird" else 0.0)

    def event(self, state: Belted) -> tuple[str, float] | None:
        """The first thing wrong with a solved state and how far past its
        crossing it is: a contact to end (``release-bird``,
        ``release-belt``), to start (``bird``, ``belt``), a switch between
        interior and tip (``to-tip``, ``to-interior``), the contact at the
        base (``base``)."""
        mode, post = state.mode, state.post
        if mode in BIRD_MODES:
            if self.pulls(post):
                return "release-bird", 0.0
            arc = post[self.POST_ARC]
            interior = mode.startswith("interior")
            if interior and arc > self.length * (1 + 1e-12):
                return "to-tip", 0.0
            if interior and arc <= BASE_FRACTION * self.length:
                return "base", 0.0
            if not interior and post[self.POST_ALONG] > 0:
                return "to-interior", 0.0
        if mode in BELT_MODES:
            if post[self.POST_BELT_FORCE] < 0:
                return "release-belt", 0.0
        elif self.depth(state, "belt") > 0.0:
            return "belt", self.depth(state, "belt")
        if mode not in BIRD_MODES and self.excess(state, "bird") > 0.0:
            return "bird", self.excess(state, "bird")
        return None

    #: where the post values hold the bird's contact arc length, the tangency
    #: d1·n (tip contact) and the belt's normal force
    POST_ARC: int
    POST_ALONG: int
    POST_BELT_FORCE: int

    def pulls(self, post: np.ndarray) -> bool:
        """Whether the bird's contact force would pull the finger into the bird."""
        raise NotImplementedError

    def switch(self, state: Belted, kind: str) -> Belted | None:
        """The state in the mode after the event ``kind``, its unknowns mapped
        (solved at the new parameters by the caller)."""
        raise NotImplementedError
