"""A spatial rod finger touching the belt, alone or with the bird: the equations.

The belt is a plane in the finger frame, n·r = e (n its upward unit normal,
e in m): below it n·r < e. A finger reaches it with its tip; the belt pushes
the tip up along n and drags it with regularised Coulomb friction against
the tip's sliding over the belt (the same law as the bird's,
:func:`~design.solvers.contact.spatial_equations.friction_vector`: the rigid
finger's velocity over the moving belt, a + B r, affine in the point).

Three modes, beside the bird-only ones of
:mod:`design.solvers.contact.spatial_equations`:

* ``belt``: the tip on the belt, the bird not touching;
* ``tip+belt``: the tip on the bird and on the belt at once (pinched);
* ``interior+belt``: the bird at arc length L < l, the finger tangent to it
  there, and the tip on the belt. The finger is then two rod segments
  (:class:`~design.solvers.beam.rod.RodTranscription`, ``segment=True``):
  [0, L] under both forces, with the moment of the tip force about r(L) at
  its end, and [L, l], clamped in the first one's end frame, under the tip
  force alone.

Unknowns z: the rod (``belt``, ``tip+belt``: one segment over [0, l];
``interior+belt``: the first segment over [0, L], then the second), the
bird's normal load ν_b = N_b l² / EI_r (not in ``belt``), u = L / l
(``interior+belt``), the belt's normal load ν_p = N_p l² / EI_r (last).

Parameters q = [l, EI_r, bird quadric (9), bird friction law (17), belt
plane (n (3), e), belt friction law (17), h_1..h_K, g_1..g_K2, stiffness...]:
the quadric and the laws as :class:`~design.solvers.contact.spatial.Quadric`
and :class:`~design.solvers.contact.spatial.FrictionLaw` give them; h the
widths of the first segment's intervals (as the bird-only modes'), g the
second segment's; ``belt`` ignores the bird's parameters.

Post (``post``): the bird-only modes' 19 values first (bird point r (3),
N_b, L, level, d1·n, normal (3), the bird's force on the finger (3), d1 at
r (3), tangential friction per unit normal (3); zero in ``belt``), then the
tip r_t (3), N_p, the tip's height above the belt n·r_t - e, d1·n at the
tip, the belt's force on the finger (3) and its tangential friction per unit
normal force (3).
"""

from __future__ import annotations

from functools import cached_property

import casadi as ca
import numpy as np

from design.solvers.beam.rod import RodStiffness, rod_transcription
from design.solvers.contact.spatial_equations import FRICTION, friction_vector, quadric_matrix
from design.solvers.newton import Chord, NewtonCache, compiled_jacobian

#: index of the belt plane (n, e) and of its friction law in q
PLANE = slice(FRICTION.stop, FRICTION.stop + 4)
BELT_FRICTION = slice(PLANE.stop, PLANE.stop + 17)
#: the second segment's collocation intervals (it carries the tip force only)
OVERHANG_INTERVALS = 2
#: post layout
POST_TIP = slice(19, 22)
POST_BELT_FORCE = 22
POST_BELT_LEVEL = 23
POST_BELT_ALONG = 24
POST_BELT_ON_FINGER = slice(25, 28)
POST_BELT_FRICTION = slice(28, 31)


def _pushed(law, r, normal):
    """The contact's force direction per unit normal force, n + t_p (t_p the
    friction's tangential part), and t_p."""
    t = friction_vector(law, r, normal)
    t_p = t - ca.dot(t, normal) * normal
    return normal + t_p, t_p


class BeltTranscription:
    """Residual R(z, q), post and shape of one belt mode (CasADi SX).

    Attributes
    ----------
    n_z, n_q : int
    residual, post, shape : casadi.Function
        ``shape``: (z, q) -> the finger's points (3, n) from base to tip (m).
    """

    def __init__(self, stiffness: RodStiffness, intervals: int, degree: int, mode: str):
        self.mode = mode
        name = "belt_" + mode.replace("+belt", "_belt")
        two = mode == "interior+belt"
        rod = rod_transcription(stiffness, intervals, degree, segment=two)
        over = rod_transcription(stiffness, OVERHANG_INTERVALS, degree, segment=True) if two \
            else None
        self.rod, self.overhang = rod, over
        K, K2, nw = rod.K, OVERHANG_INTERVALS, rod.n_w
        n_stiff = stiffness.params.size
        bird = mode != "belt"
        self.n_z = nw + (over.n_w if two else 0) + int(bird) + int(two) + 1
        self.n_q = BELT_FRICTION.stop + K + K2 + n_stiff
        z = ca.SX.sym("z", self.n_z)
        q = ca.SX.sym("q", self.n_q)
        length, ei_r = q[0], q[1]
        c, Q, law_b = q[2:5], quadric_matrix(q[5:11]), q[FRICTION]
        n_p, e_p, law_p = q[PLANE][:3], q[PLANE][3], q[BELT_FRICTION]
        widths = q[BELT_FRICTION.stop:BELT_FRICTION.stop + K]
        widths2 = q[BELT_FRICTION.stop + K:BELT_FRICTION.stop + K + K2]
        ps = q[BELT_FRICTION.stop + K + K2:]
        w = z[:nw]
        k = nw
        if two:
            w2 = z[k:k + over.n_w]
            k += over.n_w
        nu_b = z[k] if bird else 0.0
        u = z[k + 1] if two else 1.0
        nu_p = z[-1]
        L = u * length
        zero = ca.DM.zeros(3)
        # positions and frames do not depend on the loads given the unknowns
        if two:
            r_b, frame_b = rod.tip(w, ca.vertcat(zero, L, ei_r, widths, ps, 0.0, zero))
            L2 = length - L
            r2, frame2 = over.tip(w2, ca.vertcat(zero, L2, ei_r, widths2, ps, L, zero))
            r_t, frame_t = r_b + frame_b @ r2, frame_b @ frame2
        else:
            r_t, frame_t = rod.tip(w, ca.vertcat(zero, length, ei_r, widths, ps))
            r_b, frame_b = r_t, frame_t
        dir_p, t_pp = _pushed(law_p, r_t, n_p)
        eqs = []
        if bird:
            grad = Q @ (r_b - c)
            n_b = grad / ca.norm_2(grad)
            dir_b, t_bp = _pushed(law_b, r_b, n_b)
            level_b = ca.dot(r_b - c, Q @ (r_b - c)) - 1
            along_b = ca.dot(frame_b[:, 0], n_b)
        else:
            n_b = dir_b = t_bp = zero
            level_b = along_b = 0.0
        if two:
            # [0, L] under both forces and the tip force's moment about r(L);
            # [L, l] under the tip force in its own (clamped) frame
            kappa1 = u ** 2 * (nu_b * dir_b + nu_p * dir_p)
            mu_end = u / length * nu_p * ca.cross(r_t - r_b, dir_p)
            G = rod.residual(w, ca.vertcat(kappa1, L, ei_r, widths, ps, 0.0, mu_end))
            kappa2 = (L2 / length) ** 2 * nu_p * (frame_b.T @ dir_p)
            eqs += [G, over.residual(w2, ca.vertcat(kappa2, L2, ei_r, widths2, ps, L, zero))]
        else:
            kappa = nu_b * dir_b + nu_p * dir_p
            eqs.append(rod.residual(w, ca.vertcat(kappa, length, ei_r, widths, ps)))
        if bird:
            eqs.append(level_b)
        if two:
            eqs.append(along_b)
        level_p = ca.dot(n_p, r_t) - e_p
        eqs.append(level_p)
        R = ca.vertcat(*eqs)
        scale = ei_r / length ** 2
        self.residual = ca.Function(name, [z, q], [R], ["z", "q"], ["R"])
        bird_post = ca.vertcat(r_b, nu_b * scale, L, level_b, along_b, n_b,
                               nu_b * scale * dir_b, frame_b[:, 0], t_bp) if bird else \
            ca.vertcat(zero, 0.0, L, 0.0, 0.0, zero, zero, zero, zero)
        self.post = ca.Function(
            f"{name}_post", [z, q],
            [ca.vertcat(bird_post, r_t, nu_p * scale, level_p, ca.dot(frame_t[:, 0], n_p),
                        nu_p * scale * dir_p, t_pp),
             ca.mmax(ca.fabs(R))])
        # the finger's points, base to tip
        if two:
            _, pts, _ = rod.shape(w, ca.vertcat(zero, L, ei_r, widths, ps, 0.0, zero))
            _, pts2, _ = over.shape(w2, ca.vertcat(zero, L2, ei_r, widths2, ps, L, zero))
            pts = ca.horzcat(pts, r_b + frame_b @ pts2[:, 1:])
        else:
            _, pts, _ = rod.shape(w, ca.vertcat(zero, length, ei_r, widths, ps))
        self.shape = ca.Function(f"{name}_shape", [z, q], [pts])
        # dense LU, as the bird-only modes' (the loads' directions couple every node)
        self._newton = NewtonCache(
            f"{name}_newton", self.residual, "lapacklu",
            lambda: compiled_jacobian(self.residual, f"{self.residual.name()}_jac_z"))

    @cached_property
    def chord(self) -> Chord:
        """The chord method on this mode's residual (design.solvers.newton.Chord)."""
        return Chord(self.residual)

    def rootfinder(self, tolerance: float = 1e-12, max_iter: int = 30,
                   error_on_fail: bool = False, compiled_jacobian: bool = False
                   ) -> ca.Function:
        """Newton on R(z, q) = 0: (z0, q) -> z (cached; design.solvers.newton)."""
        return self._newton.get(tolerance, max_iter, error_on_fail, compiled_jacobian)


_CACHE: dict[tuple, BeltTranscription] = {}


def belt_transcription(stiffness: RodStiffness, intervals: int, degree: int, mode: str
                       ) -> BeltTranscription:
    key = (stiffness.symbolic_key(), intervals, degree, mode)
    if key not in _CACHE:
        _CACHE[key] = BeltTranscription(stiffness, intervals, degree, mode)
    return _CACHE[key]


def overhang_widths() -> np.ndarray:
    """The second segment's interval widths (fractions of its length): uniform."""
    return np.full(OVERHANG_INTERVALS, 1.0 / OVERHANG_INTERVALS)
