"""The planar (thesis's) finger against the bird and the belt.

The continuation and its events are :mod:`design.solvers.contact.belt_continuation`'s;
here are the planar equations (bird-only: equations.py in conic form; with
the belt: planar_belt_equations.py), the geometry in the bending plane and
the maps between the modes' unknowns.

The bird's friction is the planar model's: τµ along the sliding tangent, at
the edge of sliding. Its sense is given with the bird (the finger model
decides it: from the sliding at first touch, or the thesis's tipwards
convention) and kept while the contact lasts; a finger on the belt is not
checked for friction reversals.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from design.physics.contact import ContactSolution, FingerPose, grazing, straight_overlap
from design.physics.ellipse import Ellipse
from design.solvers.beam.collocation import legendre_tables
from design.solvers.contact.belt_continuation import (BELT_MODES, BIRD_MODES, Belted,
                                                    BeltedContact, Deepest, Plane, deepest)
from design.solvers.contact.planar_belt_equations import (POST_BELT_FORCE, POST_BELT_ON_FINGER,
                                                        POST_TIP, planar_belt_transcription)
from design.solvers.contact.robust import BASE_FRACTION, RobustContact, _State
from design.solvers.contact.spatial_belt import _evaluate, _nodes
from design.solvers.contact.spatial_belt_equations import overhang_widths

#: a conic for the belt-only modes, which ignore the bird
_NO_BIRD = np.array([0.0, 1.0, 1.0, 0.0, 1.0])
#: the belt's friction law without friction (any positive regularisation speed)
NO_BELT_FRICTION = np.array([0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0])


class PlanarBeltContact(BeltedContact):
    """The contact of one planar finger with the bird (its section by the
    bending plane, a conic) and the belt (a line in that plane).

    Parameters
    ----------
    contact : RobustContact
        The finger's bird-only solver: finger, mesh, tolerance and the
        conic-form transcriptions are shared.
    """

    n_bird = 5

    def __init__(self, contact: RobustContact):
        super().__init__()
        self.contact = contact
        self.length = contact.finger.length
        self.tolerance, self.max_steps = contact.tolerance, contact.max_steps
        self.widths2 = overhang_widths()
        self.tr = {m: planar_belt_transcription(contact.finger.stiffness, contact.intervals,
                                                contact.degree, m) for m in BELT_MODES}
        self.n_beam = self.tr["belt"].beam.n_w
        self.n_over = self.tr["interior+belt"].overhang.n_w
        self.tau = legendre_tables(contact.degree)[0]

    # ----------------------------------------------------------------- API
    def solve(self, conic: tuple[np.ndarray, np.ndarray] | None, tau_mu: float, line: Plane,
              belt: np.ndarray, previous: Belted | None = None, detail: bool = True
              ) -> tuple[ContactSolution, Belted | None]:
        """The finger against the bird's section ``conic`` = (centre, B) in
        the finger frame (None when it cannot be reached) with the signed
        friction ``tau_mu``, and the belt's ``line`` under the law ``belt``
        ([µ, ε, a (2), G (4)]: the tip's in-plane sliding over the belt, a +
        G p), continued from ``previous``."""
        bird = None if conic is None else np.concatenate(
            [conic[0], [conic[1][0, 0], conic[1][0, 1], conic[1][1, 1]]])
        if bird is not None and _level(bird, np.zeros((2, 1)))[0] <= 0.0:
            return self._failed("the finger base is inside the object: invalid pose"), None
        target = Belted("free", None, bird, np.array([tau_mu]), line, np.asarray(belt, float))
        state, msg = self.continued(target, previous)
        if state is None:
            return self._failed(msg), None
        return self._solution(state, msg, detail), self.with_lu(state) if detail else state

    def adopt(self, state, line: Plane, belt: np.ndarray) -> Belted:
        """A bird-only state of :class:`RobustContact` to continue here, with
        the belt's ``line`` lowered to its tip."""
        center, B = state.conic if state.conic is not None else \
            (np.asarray(state.ellipse.center, float), state.ellipse.matrix)
        bird = np.concatenate([center, [B[0, 0], B[0, 1], B[1, 1]]])
        return self.lowered(Belted(state.mode, state.z, bird, np.array([state.tau_mu]), line,
                                   np.asarray(belt, float), side=state.side))

    def bird_only(self, state: Belted):
        """A state off the belt as :class:`RobustContact`'s (None when free)."""
        if state.mode not in ("interior", "tip"):
            return None
        return _State(state.mode, state.z, None, float(state.friction[0]), state.side,
                      state.post[:12], (state.bird[:2].copy(), _matrix(state.bird)))

    # --------------------------------------------------------- the model's
    def free(self, target: Belted) -> Belted:
        bird, side = target.bird, 0
        if bird is not None and _overlap(bird, self.length) < 0.0:
            side = self._entering_side(bird)
            graze = grazing(_ellipse(bird), self.length, side)
            bird = bird.copy()
            bird[1] -= side * graze[0]
        tip = np.array([self.length, 0.0])
        return Belted("free", None, bird, np.zeros(1), target.plane.lowered_to(tip),
                      NO_BELT_FRICTION, side=side)

    def transcription(self, mode: str):
        return self.tr[mode] if mode in BELT_MODES else self.contact._conic[mode]

    def q(self, state: Belted) -> np.ndarray:
        c = self.contact
        bird = _NO_BIRD if state.bird is None else state.bird
        head = np.concatenate([[self.length, c.ei_ref], bird, state.friction])
        if state.mode in BELT_MODES:
            return np.concatenate([head, state.plane.params, state.belt, c.widths, self.widths2,
                                   c.finger.stiffness.params])
        return np.concatenate([head, c.widths, c.finger.stiffness.params])

    def solved(self, state: Belted, post: np.ndarray) -> Belted | None:
        mode = state.mode
        if mode in BIRD_MODES:
            if post[3] < 0:                       # F < 0 with α is F > 0 with α + π
                z = state.z.copy()
                k = self._kappa_index(mode)
                z[k], z[k + 1] = -z[k], z[k + 1] + np.pi
                state = replace(state, z=z)
                post = self.calls(mode)[0](z, self.q(state))[0].ravel()
            if state.side * post[11] <= 0:        # bent the other way: another branch
                return None
        if mode in BELT_MODES:
            return replace(state, post=post)
        psi, arc = post[2], post[5]
        tip = post[:2] + (self.length - arc) * np.array([np.cos(psi), np.sin(psi)])
        t_f = np.array([np.cos(psi), np.sin(psi)])
        return replace(state, post=np.concatenate([
            post[:12], tip, [0.0, float(state.plane.level(tip[:, None])[0]),
                             float(t_f @ state.plane.normal), 0.0, 0.0]]))

    POST_ARC, POST_ALONG, POST_BELT_FORCE = 5, 7, POST_BELT_FORCE

    def pulls(self, post: np.ndarray) -> bool:
        return bool(post[3] > 0 and post[8] <= 0)

    def depth(self, state: Belted, kind: str) -> float:
        if kind == "belt":
            return -float(state.plane.level(self.tip(state)[:, None])[0])
        return -np.inf if state.bird is None else self._bird_depth(state)

    def switch(self, state: Belted, kind: str) -> Belted | None:
        mode, z, n1, n2 = state.mode, state.z, self.n_beam, self.n_over
        if kind == "belt":
            if mode == "free":
                return replace(state, mode="belt", z=np.zeros(n1 + 1))
            z_new = np.append(z, 0.0) if mode == "tip" else \
                np.concatenate([z[:n1], np.zeros(n2), z[n1:n1 + 3], [0.0]])
            return replace(state, mode=f"{mode}+belt", z=z_new)
        if kind == "bird":
            touch = self._touch(state)
            if touch is None:
                return None
            arc, side, alpha = touch
            at_tip = arc >= self.length * (1 - 1e-12)
            force = [0.0, alpha]
            if mode == "free":
                extra = force if at_tip else [*force, arc / self.length]
                return replace(state, mode="tip" if at_tip else "interior", side=side,
                               z=np.append(np.zeros(n1), extra))
            w, nu_p = z[:n1], z[-1]
            if at_tip:
                return replace(state, mode="tip+belt", side=side,
                               z=np.concatenate([w, force, [nu_p]]))
            u = arc / self.length
            return replace(state, mode="interior+belt", side=side,
                           z=np.concatenate([*self._split(w, u), force, [u, nu_p]]))
        if kind == "release-belt":
            if mode == "belt":
                return replace(state, mode="free", z=None, post=None)
            if mode == "tip+belt":
                return replace(state, mode="tip", z=z[:-1])
            return replace(state, mode="interior", z=np.concatenate([z[:n1], z[n1 + n2:-1]]))
        if kind == "release-bird":
            if mode in ("interior", "tip"):
                return replace(state, mode="free", z=None, post=None, side=0)
            if mode == "tip+belt":
                return replace(state, mode="belt", z=np.append(z[:n1], z[-1]), side=0)
            joined = self._join(z[:n1], z[n1:n1 + n2], z[-2])
            return replace(state, mode="belt", z=np.append(joined, z[-1]), side=0)
        if kind == "to-tip":
            if mode == "interior":
                return replace(state, mode="tip", z=z[:-1])
            return replace(state, mode="tip+belt",
                           z=np.concatenate([z[:n1], z[n1 + n2:n1 + n2 + 2], [z[-1]]]))
        if mode == "tip":                                           # to-interior
            return replace(state, mode="interior", z=np.append(z, 1.0))
        return replace(state, mode="interior+belt",
                       z=np.concatenate([z[:n1], np.zeros(n2), z[n1:n1 + 2], [1.0, z[-1]]]))

    # ---------------------------------------------------------- geometry
    def _entering_side(self, bird: np.ndarray) -> int:
        """The side the straight finger is bent to by a bird it enters: the one
        it has to bend less to clear (as :class:`RobustContact`)."""
        ell = _ellipse(bird)
        up, down = grazing(ell, self.length, +1), grazing(ell, self.length, -1)
        if up is None or down is None:
            return 1 if down is None else -1
        return 1 if up[0] <= down[0] else -1

    def _kappa_index(self, mode: str) -> int:
        return self.n_beam + (self.n_over if mode == "interior+belt" else 0)

    def tip(self, state: Belted) -> np.ndarray:
        return np.array([self.length, 0.0]) if state.mode == "free" else state.post[POST_TIP]

    def _points(self, state: Belted) -> np.ndarray:
        """The finger's points (2, n), base to tip."""
        if state.mode == "free":
            return np.vstack([np.linspace(0.0, self.length, 16), np.zeros(16)])
        shape = self.calls(state.mode)[1](state.z, self.q(state))
        if state.mode in BELT_MODES:
            return shape[0]
        x, y = shape[1].ravel(), shape[2].ravel()
        post = state.post
        rest = np.linspace(0.0, self.length - post[5], 6)[1:]
        t_f = np.array([np.cos(post[2]), np.sin(post[2])])
        return np.hstack([np.vstack([x, y]), post[:2, None] + t_f[:, None] * rest[None, :]])

    def _deepest(self, state: Belted) -> Deepest:
        """Where a ``belt`` state's finger goes deepest into the bird."""
        points, tangents = self.calls(state.mode)[1](state.z, self.q(state))
        return deepest(points, tangents, state.bird[:2], _matrix(state.bird))

    def _bird_depth(self, state: Belted) -> float:
        """How deep the finger (not touching the bird) is inside it (m; ≤ 0 outside)."""
        if state.mode == "free":
            level = _overlap(state.bird, self.length)
        elif state.mode == "belt":
            level = self._deepest(state).level
        else:                                   # touching the bird, grazing it
            level = float(np.min(_level(state.bird, self._points(state))))
        B = _matrix(state.bird)
        return -level / (2.0 * np.sqrt(np.linalg.eigvalsh(B).max()))

    def _touch(self, state: Belted) -> tuple[float, int, float] | None:
        """Where the finger (free or on the belt) enters the bird most deeply:
        arc length (m), the side it is bent to, and the force direction α of
        a first touch there."""
        tau_mu = float(state.friction[0])
        if state.mode == "free":
            side = state.side or self._entering_side(state.bird)
            graze = grazing(_ellipse(state.bird), self.length, side)
            if graze is None:
                return None
            arc, psi, point = graze[1], 0.0, np.array([graze[1], 0.0])
        else:
            found = self._deepest(state)
            arc, point = found.fraction * self.length, found.point
            if arc <= BASE_FRACTION * self.length:
                return None
            psi = float(np.arctan2(found.tangent[1], found.tangent[0]))
            n_f = np.array([-np.sin(psi), np.cos(psi)])
            side = 1 if _gradient(state.bird, point) @ n_f > 0 else -1
        t_f = np.array([np.cos(psi), np.sin(psi)])
        normal = _gradient(state.bird, point)
        normal /= np.linalg.norm(normal)
        if arc < self.length * (1 - 1e-12):
            # a first touch inside the span: the surface's normal is the finger's
            normal = side * np.array([-np.sin(psi), np.cos(psi)])
            t_c = t_f
        else:
            t_c = t_f - (t_f @ normal) * normal
            t_c = t_c / np.linalg.norm(t_c) if np.linalg.norm(t_c) > 0 else t_f
        e = normal + tau_mu * t_c
        return arc, side, float(np.arctan2(e[1], -e[0]))

    def _split(self, w: np.ndarray, u: float) -> tuple[np.ndarray, np.ndarray]:
        """A whole-finger beam state (over [0, l], μ = M l / EI_r) as the two
        segments of interior+belt split at u = L / l (interpolated): the
        second in the first's end angle."""
        widths = self.contact.widths
        first = _evaluate(w, widths, self.tau, u * _nodes(widths, self.tau))
        first[1] *= u
        psi_at = float(_evaluate(w, widths, self.tau, np.array([u]))[0, 0])
        second = _evaluate(w, widths, self.tau, u + (1.0 - u) * _nodes(self.widths2, self.tau))
        second[0] -= psi_at
        second[1] *= 1.0 - u
        return first.T.ravel(), second.T.ravel()

    def _join(self, w1: np.ndarray, w2: np.ndarray, u: float) -> np.ndarray:
        """The inverse of :meth:`_split`: the two segments as one beam state."""
        widths = self.contact.widths
        nodes = _nodes(widths, self.tau)
        psi_end = float(_evaluate(w1, widths, self.tau, np.array([1.0]))[0, 0])
        out = np.zeros((2, nodes.size))
        inner = nodes < u
        out[:, inner] = _evaluate(w1, widths, self.tau, nodes[inner] / u)
        out[1, inner] /= u
        outer = _evaluate(w2, self.widths2, self.tau, (nodes[~inner] - u) / (1.0 - u))
        out[0, ~inner] = outer[0] + psi_end
        out[1, ~inner] = outer[1] / (1.0 - u)
        return out.T.ravel()

    # -------------------------------------------------------------- output
    def _failed(self, message: str) -> ContactSolution:
        s = np.linspace(0.0, self.length, 2)
        return ContactSolution(False, 0.0, 0.0, 0.0, (np.nan, np.nan), 0.0, False, None, "none",
                               FingerPose(0.0, 0.0), s, s.copy(), np.zeros(2), False,
                               message=message)

    def _solution(self, state: Belted, msg: str, detail: bool) -> ContactSolution:
        """The state as a :class:`ContactSolution` with the belt's part."""
        mode, post = state.mode, state.post
        pts = self._points(state) if detail else np.array([[0.0, self.tip(state)[0]],
                                                           [0.0, self.tip(state)[1]]])
        extras = {"mode": mode, "z": None if state.z is None else state.z.copy(),
                  "friction_ratio": float(state.friction[0])}
        on = mode in BELT_MODES
        belt = {"below_belt": float(max(0.0, -state.plane.level(pts).min())) if detail else 0.0,
                "belt_force": -post[POST_BELT_ON_FINGER] if on else None,
                "belt_normal_force": float(post[POST_BELT_FORCE]) if on else 0.0,
                "belt_point": post[POST_TIP].copy() if on else None}
        s = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(pts, axis=1)))])
        if mode not in BIRD_MODES:
            return ContactSolution(False, 0.0, 0.0, 0.0, (np.nan, np.nan), 0.0, False, None,
                                   "none", FingerPose(0.0, 0.0), s, pts[0], pts[1], True,
                                   self.newton_iterations, msg, extras=extras, **belt)
        tau_mu = float(state.friction[0])
        label = "none" if tau_mu == 0.0 else ("tipward" if tau_mu > 0 else "baseward")
        return ContactSolution(
            True, float(post[3]), float(post[4]), float(post[5]), (float(post[0]),
                                                                   float(post[1])),
            float(post[2]), mode.startswith("tip"), "push" if state.side > 0 else "pull", label,
            FingerPose(0.0, 0.0), s, pts[0], pts[1], True, self.newton_iterations, msg,
            0.0 if detail else float("nan"), extras=extras, **belt)


def _matrix(bird: np.ndarray) -> np.ndarray:
    return np.array([[bird[2], bird[3]], [bird[3], bird[4]]])


def _level(bird: np.ndarray, pts: np.ndarray) -> np.ndarray:
    d = pts - bird[:2, None]
    return np.einsum("in,ij,jn->n", d, _matrix(bird), d) - 1.0


def _gradient(bird: np.ndarray, point: np.ndarray) -> np.ndarray:
    return 2.0 * _matrix(bird) @ (point - bird[:2])


def _overlap(bird: np.ndarray, length: float) -> float:
    return straight_overlap(bird[:2], _matrix(bird), length)


def _ellipse(bird: np.ndarray) -> Ellipse:
    return Ellipse.from_conic(bird[:2], _matrix(bird))
