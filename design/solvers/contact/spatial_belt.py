"""A spatial rod finger against the bird and the belt (the ``spatial`` model).

The continuation and its events are :mod:`design.solvers.contact.belt_continuation`'s;
here are the rod's equations (bird-only: spatial_equations.py; with the
belt: spatial_belt_equations.py), its geometry and the maps between the
modes' unknowns. The finger's points below the belt away from its tip are
reported as the solution's ``below_belt``.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from design.physics.rod import quaternion_rotation
from design.solvers.beam.collocation import legendre_tables
from design.solvers.beam.rod import N_STATE
from design.solvers.contact.belt_continuation import (BELT_MODES, BIRD_MODES, COMMIT, TRIAL,
                                                    Belted, BeltedContact, Deepest, Plane,
                                                    deepest)
from design.solvers.contact.robust import BASE_FRACTION
from design.solvers.contact.spatial import (NO_FRICTION, FrictionLaw, Quadric, SpatialContact,
                                          SpatialSolution, SpatialState, grazing_shift,
                                          segment_level)
from design.solvers.contact.spatial_belt_equations import (POST_BELT_FORCE, POST_BELT_ON_FINGER,
                                                         POST_TIP, belt_transcription,
                                                         overhang_widths)

#: a quadric for the belt-only modes, which ignore the bird
_NO_BIRD = Quadric(np.array([0.0, 0.0, 1.0]), np.eye(3))
#: the states whose deepest point into the bird is kept
DEEPEST_KEPT = 16


class SpatialBeltContact(BeltedContact):
    """The contact of one spatial rod finger with the bird and the belt.

    Parameters
    ----------
    contact : SpatialContact
        The finger's bird-only solver: its finger, mesh, tolerance and
        bird-only transcriptions are shared.
    """

    n_bird = 9

    def __init__(self, contact: SpatialContact):
        super().__init__()
        self.contact = contact
        self.length = contact.finger.length
        self.tolerance, self.max_steps = contact.tolerance, contact.max_steps
        self.widths2 = overhang_widths()
        self.belt_tail = np.concatenate([contact.widths, self.widths2, contact.stiffness.params])
        rod = contact.tr["interior"].rod
        self.n_rod = rod.n_w
        self.tr = {m: belt_transcription(contact.stiffness, rod.K, rod.d, m) for m in BELT_MODES}
        self.n_over = self.tr["interior+belt"].overhang.n_w
        self.tau, _, self.ends = legendre_tables(rod.d)[:3]
        self._deepest_of: dict = {}

    # ----------------------------------------------------------------- API
    def solve(self, quadric: Quadric | None, friction, plane: Plane, belt,
              previous: Belted | None = None, detail: bool = True, trial: bool = False
              ) -> tuple[SpatialSolution, Belted | None]:
        """The finger against ``quadric`` (the bird in the finger frame; None
        when it cannot be reached) under the friction law ``friction``, and
        the belt ``plane`` under the law ``belt``, continued from
        ``previous`` (``trial``: an integrator's trial from its accepted
        state, lost at a coarser stall). Returns the solution, whose extras'
        ``continuation_lost`` says whether it was found afresh, and the
        state to continue from."""
        if quadric is not None and quadric.base_level <= 0.0:
            return self._failed("the finger base is inside the object: invalid pose"), None
        target = Belted("free", None, None if quadric is None else quadric.params,
                        FrictionLaw.of(friction).params, plane, FrictionLaw.of(belt).params)
        state, msg = self.continued(target, previous, TRIAL if trial else COMMIT)
        if state is None:
            return self._failed(msg), None
        sol = self._solution(state, msg)
        sol.extras["continuation_lost"] = self.lost
        return self.detailed(sol, state) if detail else (sol, state)

    def detailed(self, sol: SpatialSolution, state: Belted) -> tuple[SpatialSolution, Belted]:
        """What an accepted instant keeps of a solve without detail: the
        solution with the finger's shape and how far it lies below the belt,
        and the state with its Jacobian's LU factors (the chord method's)."""
        pts = self._points(state)
        return (replace(sol, shape_points=pts,
                        below_belt=float(max(0.0, -state.plane.level(pts).min()))),
                self.with_lu(state))

    def adopt(self, state: SpatialState, plane: Plane, belt) -> Belted:
        """A bird-only state of :class:`SpatialContact` to continue here, with
        the belt ``plane`` lowered to its tip: the belt then comes in from
        first touch."""
        return self.lowered(Belted(state.mode, state.z, state.quadric.params, state.friction,
                                   plane, FrictionLaw.of(belt).params))

    def bird_only(self, state: Belted) -> SpatialState | None:
        """A state off the belt as :class:`SpatialContact`'s (None when free)."""
        if state.mode not in ("interior", "tip"):
            return None
        return SpatialState(state.mode, state.z, Quadric.from_params(state.bird), state.friction,
                            state.post[:19])

    # --------------------------------------------------------- the model's
    def free(self, target: Belted) -> Belted:
        bird = target.bird
        if bird is not None:
            quadric = Quadric.from_params(bird)
            if segment_level(quadric, self.length) < 0.0:
                graze = grazing_shift(quadric, self.length)
                bird = quadric.shifted(graze[0]).params if graze is not None else None
        tip = np.array([self.length, 0.0, 0.0])
        return Belted("free", None, bird, NO_FRICTION, target.plane.lowered_to(tip), NO_FRICTION)

    def transcription(self, mode: str):
        return self.tr[mode] if mode in BELT_MODES else self.contact.tr[mode]

    def q(self, state: Belted) -> np.ndarray:
        c = self.contact
        bird = _NO_BIRD.params if state.bird is None else state.bird
        if state.mode in BELT_MODES:
            return np.concatenate([[self.length, c.ei_ref], bird, state.friction,
                                   state.plane.params, state.belt, self.belt_tail])
        return np.concatenate([[self.length, c.ei_ref], bird, state.friction, c.tail])

    def solved(self, state: Belted, post: np.ndarray) -> Belted:
        if state.mode in BELT_MODES:
            return replace(state, post=post)
        # a bird-only mode: the tip (straight beyond the contact) and its height
        tip = post[:3] + post[13:16] * (self.length - post[4])
        level = float(state.plane.level(tip[:, None])[0])
        return replace(state, post=np.concatenate([
            post[:19], tip, [0.0, level, float(post[13:16] @ state.plane.normal)], np.zeros(6)]))

    POST_ARC, POST_ALONG, POST_BELT_FORCE = 4, 6, POST_BELT_FORCE

    def pulls(self, post: np.ndarray) -> bool:
        return bool(post[3] < 0)

    def depth(self, state: Belted, kind: str) -> float:
        if kind == "belt":
            return -float(state.plane.level(self.tip(state)[:, None])[0])
        return -np.inf if state.bird is None else self._bird_depth(state)

    def switch(self, state: Belted, kind: str) -> Belted | None:
        mode, z, n1, n2 = state.mode, state.z, self.n_rod, self.n_over
        if kind == "belt":
            if mode == "free":
                return replace(state, mode="belt", z=np.append(self._straight(), 0.0))
            extra = [0.0] if mode == "tip" else None
            z_new = np.append(z, extra) if extra else \
                np.concatenate([z[:n1], self._straight_overhang(), z[n1:n1 + 2], [0.0]])
            return replace(state, mode=f"{mode}+belt", z=z_new)
        if kind == "bird":
            arc = self._grazing(state)
            if arc is None:
                return None
            at_tip = arc >= self.length * (1 - 1e-12)
            if mode == "free":
                extra = [0.0] if at_tip else [0.0, arc / self.length]
                return replace(state, mode="tip" if at_tip else "interior",
                               z=np.append(self._straight(), extra))
            w, nu_p = z[:n1], z[-1]
            if at_tip:
                return replace(state, mode="tip+belt", z=np.concatenate([w, [0.0, nu_p]]))
            u = arc / self.length
            return replace(state, mode="interior+belt",
                           z=np.concatenate([*self._split(w, u), [0.0, u, nu_p]]))
        if kind == "release-belt":
            if mode == "belt":
                return replace(state, mode="free", z=None, post=None)
            if mode == "tip+belt":
                return replace(state, mode="tip", z=z[:n1 + 1])
            return replace(state, mode="interior", z=np.concatenate([z[:n1], z[n1 + n2:-1]]))
        if kind == "release-bird":
            if mode in ("interior", "tip"):
                return replace(state, mode="free", z=None, post=None)
            if mode == "tip+belt":
                return replace(state, mode="belt", z=np.append(z[:n1], z[-1]))
            joined = self._join(z[:n1], z[n1:n1 + n2], z[n1 + n2 + 1])
            return replace(state, mode="belt", z=np.append(joined, z[-1]))
        if kind == "to-tip":
            if mode == "interior":
                return replace(state, mode="tip", z=z[:n1 + 1])
            return replace(state, mode="tip+belt", z=np.concatenate([z[:n1], [z[n1 + n2], z[-1]]]))
        if mode == "tip":                                           # to-interior
            return replace(state, mode="interior", z=np.append(z, 1.0))
        return replace(state, mode="interior+belt",
                       z=np.concatenate([z[:n1], self._straight_overhang(), [z[n1], 1.0, z[-1]]]))

    # ---------------------------------------------------------- geometry
    def tip(self, state: Belted) -> np.ndarray:
        return np.array([self.length, 0.0, 0.0]) if state.mode == "free" else state.post[POST_TIP]

    def _points(self, state: Belted) -> np.ndarray:
        """The finger's points (3, n), base to tip."""
        if state.mode == "free":
            return np.vstack([np.linspace(0.0, self.length, 16), np.zeros((2, 16))])
        shape = self.calls(state.mode)[1](state.z, self.q(state))
        if state.mode in BELT_MODES:
            return shape[0]
        r = shape[1]
        post = state.post
        rest = np.linspace(0.0, self.length - post[4], 6)[1:]
        return np.hstack([r, post[:3, None] + post[13:16, None] * rest[None, :]])

    def _tangents(self, state: Belted) -> np.ndarray:
        """The unit tangents d1 (3, n) at :meth:`_points` of a ``belt`` state:
        its nodes' quaternions, the tip's by the last interval's end values."""
        nodes = state.z[:self.n_rod].reshape(-1, N_STATE)[:, :4]
        quats = np.vstack([nodes, self.ends @ nodes[-self.tau.size:]])
        return quaternion_rotation(quats.T)[:, 0]

    def _bird_depth(self, state: Belted) -> float:
        """How deep the finger (not touching the bird) is inside it (m; ≤ 0 outside)."""
        quadric = Quadric.from_params(state.bird)
        if state.mode == "free":
            level = segment_level(quadric, self.length)
        elif state.mode == "belt":
            level = self._deepest(state, quadric).level
        else:                                   # touching the bird, grazing it
            level = float(np.min(quadric.level(self._points(state))))
        return -level / (2.0 * np.sqrt(np.linalg.eigvalsh(quadric.matrix).max()))

    def _deepest(self, state: Belted, quadric: Quadric) -> Deepest:
        """Where a ``belt`` state's finger goes deepest into the bird (kept for
        the last few states: a continuation step asks it of the same state
        for its event, its clearance and its switch)."""
        key = (state.mode, state.z.tobytes(), self.q(state).tobytes(),
               None if state.post is None else state.post.tobytes(), quadric.params.tobytes())
        found = self._deepest_of.get(key)
        if found is None:
            if len(self._deepest_of) >= DEEPEST_KEPT:
                self._deepest_of.clear()
            found = self._deepest_of[key] = deepest(self._points(state), self._tangents(state),
                                                    quadric.center, quadric.matrix)
        return found

    def _grazing(self, state: Belted) -> float | None:
        """Arc length (m) where the finger (free or on the belt) enters the
        bird most deeply."""
        quadric = Quadric.from_params(state.bird)
        if state.mode == "free":
            graze = grazing_shift(quadric, self.length)
            return None if graze is None else graze[1]
        arc = self.length * self._deepest(state, quadric).fraction
        return arc if arc > BASE_FRACTION * self.length else None

    def _straight(self) -> np.ndarray:
        return self.contact.tr["interior"].rod.straight()

    def _straight_overhang(self) -> np.ndarray:
        return self.tr["interior+belt"].overhang.straight()

    def _split(self, w: np.ndarray, u: float) -> tuple[np.ndarray, np.ndarray]:
        """A whole-finger rod state (over [0, l], μ = m l / EI_r) as the two
        segments of interior+belt split at u = L / l (interpolated): the
        second in the first's end frame."""
        widths = self.contact.widths
        first = _evaluate(w, widths, self.tau, u * _nodes(widths, self.tau))
        first[4:] *= u
        at = _unit(_evaluate(w, widths, self.tau, np.array([u]))[:4, 0])
        second = _evaluate(w, widths, self.tau, u + (1.0 - u) * _nodes(self.widths2, self.tau))
        back = _conjugate(at)
        second[:4] = _multiply(back, second[:4])
        second[4:] = quaternion_rotation(at).T @ second[4:] * (1.0 - u)
        return first.T.ravel(), second.T.ravel()

    def _join(self, w1: np.ndarray, w2: np.ndarray, u: float) -> np.ndarray:
        """The inverse of :meth:`_split`: the two segments as one rod state."""
        widths = self.contact.widths
        nodes = _nodes(widths, self.tau)
        end = _unit(_evaluate(w1, widths, self.tau, np.array([1.0]))[:4, 0])
        out = np.zeros((7, nodes.size))
        inner = nodes < u
        out[:, inner] = _evaluate(w1, widths, self.tau, nodes[inner] / u)
        out[4:, inner] /= u
        outer = _evaluate(w2, self.widths2, self.tau, (nodes[~inner] - u) / (1.0 - u))
        out[:4, ~inner] = _multiply(end, outer[:4])
        out[4:, ~inner] = quaternion_rotation(end) @ outer[4:] / (1.0 - u)
        return out.T.ravel()

    # -------------------------------------------------------------- output
    def _failed(self, message: str) -> SpatialSolution:
        return SpatialSolution(False, np.zeros(3), 0.0, None, None, 0.0, False, False, message,
                               shape_points=np.vstack([np.linspace(0.0, self.length, 2),
                                                       np.zeros((2, 2))]))

    def _solution(self, state: Belted, msg: str) -> SpatialSolution:
        """The state as a :class:`SpatialSolution` with the belt's part, without
        the finger's shape (:meth:`detailed` adds it)."""
        if state.held < 1.0:
            msg = "; ".join(m for m in (msg, f"sticking: the finger carries {state.held:.0%} of "
                                             f"the sliding friction (no equilibrium beyond)") if m)
        mode, post = state.mode, state.post
        belt = {}
        if mode in BELT_MODES:
            belt.update(belt_force=-post[POST_BELT_ON_FINGER],
                        belt_normal_force=float(post[POST_BELT_FORCE]),
                        belt_point=post[POST_TIP].copy())
        extras = {"mode": mode, "z": None if state.z is None else state.z.copy(),
                  "iterations": self.newton_iterations, "friction_held": state.held}
        if mode not in BIRD_MODES:
            return SpatialSolution(False, np.zeros(3), 0.0, None, None, 0.0, False, True, msg,
                                   extras=extras, **belt)
        extras["friction"] = post[16:19].copy()
        return SpatialSolution(True, -post[10:13], float(post[3]), post[:3].copy(),
                               post[7:10].copy(), float(post[4]), mode.startswith("tip"), True,
                               msg, extras=extras, **belt)


# ------------------------------------------------------ rod state helpers
def _nodes(widths: np.ndarray, tau: np.ndarray) -> np.ndarray:
    """u of each stored node: every interval's start and collocation points."""
    starts = np.concatenate([[0.0], np.cumsum(widths)[:-1]])
    return (starts[:, None] + tau[None, :] * widths[:, None]).ravel()


def _evaluate(w: np.ndarray, widths: np.ndarray, tau: np.ndarray, u: np.ndarray) -> np.ndarray:
    """The collocated state (states per node, n) at u in [0, 1], by each
    interval's Lagrange polynomial through its d + 1 nodes."""
    d1 = tau.size
    states = w.reshape(widths.size, d1, -1)
    edges = np.concatenate([[0.0], np.cumsum(widths)])
    j = np.clip(np.searchsorted(edges, u, side="right") - 1, 0, widths.size - 1)
    s = (u - edges[j]) / widths[j]
    # basis[i, k] = Π_{r≠k} (s_i - τ_r) / (τ_k - τ_r): the r = k factor set to 1
    own = np.eye(d1, dtype=bool)
    gaps = np.where(own, 1.0, tau[:, None] - tau[None, :])
    ratios = (s[:, None, None] - tau[None, None, :]) / gaps
    basis = np.where(own, 1.0, ratios).prod(axis=2)
    return np.einsum("ikn,ik->ni", states[j], basis)


def _unit(q: np.ndarray) -> np.ndarray:
    return q / np.linalg.norm(q)


def _multiply(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Quaternion products a ⊗ b, (w, x, y, z): a (4,), b (4,) or (4, n)."""
    w1, (x1, y1, z1), w2, (x2, y2, z2) = a[0], a[1:], b[0], b[1:]
    return np.array([w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2,
                     w1 * x2 + w2 * x1 + y1 * z2 - z1 * y2,
                     w1 * y2 + w2 * y1 + z1 * x2 - x1 * z2,
                     w1 * z2 + w2 * z1 + x1 * y2 - y1 * x2])


def _conjugate(q: np.ndarray) -> np.ndarray:
    return np.concatenate([[q[0]], -q[1:]])
