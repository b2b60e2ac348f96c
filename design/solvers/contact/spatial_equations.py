"""A spatial rod finger against an ellipsoid: the contact equations in CasADi.

The 3-D counterpart of :mod:`design.solvers.contact.equations`. In the finger
frame the object is the quadric (r - c)ᵀ Q (r - c) = 1 (Q symmetric
positive definite); n = Q (r - c) / |Q (r - c)| is its outward normal.

Unknowns z: the collocated rod w (:mod:`design.solvers.beam.rod`), the
normal load ν = N l² / EI_r (N the normal force, l the finger length) and,
for contact inside the span, u = L / l. The force on the finger at its
contact point r(L) is

    F = N (n + t - (t·n) n),

t the friction force per unit normal force, given by the friction law of
:class:`FrictionLaw`: a fixed vector t0 plus regularised Coulomb friction
against the finger's sliding at the contact point itself,

    t = t0 - µ w / sqrt(|w|² + ε²),   w = (I - n nᵀ)(a + B r),

a + B r the rigid finger's velocity over the object's surface at r (m/s,
affine in r for rigid motions). Solving the law with the contact makes the
friction a function of the pose and rates alone, not of an earlier
solution's contact point (its normal part is dropped from t). Equations:
the rod, G(w; F, L) = 0; the contact
point on the surface, (r - c)ᵀ Q (r - c) - 1 = 0; and for *interior*
contact the rod tangent to the surface there, d1 · n = 0. *Tip* contact
(L = l) drops the tangency.

Parameters q = [l, EI_r, c (3), Q00, Q01, Q02, Q11, Q12, Q22, friction law
(17: t0 (3), µ, ε, a (3), B (9, row-major)), h_1..h_K, stiffness...].
"""

from __future__ import annotations

from functools import cached_property

import casadi as ca
import numpy as np

from design.solvers.beam.rod import RodStiffness, rod_transcription
from design.solvers.newton import Chord, NewtonCache, compiled_jacobian

MODES = ("interior", "tip")
#: index of the quadric (c, Q) in q
QUADRIC = slice(2, 11)
#: index of the friction law in q
FRICTION = slice(11, 28)


def quadric_matrix(p):
    """Symmetric Q (3, 3) from its 6 upper entries (CasADi)."""
    return ca.vertcat(ca.horzcat(p[0], p[1], p[2]), ca.horzcat(p[1], p[3], p[4]),
                      ca.horzcat(p[2], p[4], p[5]))


def quadric_params(c: np.ndarray, Q: np.ndarray) -> np.ndarray:
    """[c (3), Q00, Q01, Q02, Q11, Q12, Q22]."""
    return np.concatenate([c, Q[0, :3], Q[1, 1:3], Q[2, 2:3]])


def friction_vector(law, r, normal):
    """t = t0 - µ w / sqrt(|w|² + ε²), w the tangential part of a + B r (CasADi)."""
    t0, mu, eps, a, B = law[0:3], law[3], law[4], law[5:8], ca.reshape(law[8:17], 3, 3).T
    v = a + B @ r
    w = v - ca.dot(v, normal) * normal
    return t0 - mu * w / ca.sqrt(ca.dot(w, w) + eps ** 2)


class SpatialContactTranscription:
    """Residual R(z, q) and helpers for one contact mode.

    Attributes
    ----------
    rod : RodTranscription
    n_z, n_q : int
    residual, rootfinder, post, shape, sensitivity : casadi.Function
    """

    def __init__(self, stiffness: RodStiffness, intervals: int, degree: int, mode: str):
        self.mode = mode
        self.rod = rod = rod_transcription(stiffness, intervals, degree)
        K, nw = rod.K, rod.n_w
        self.n_z = nw + (2 if mode == "interior" else 1)
        self.n_q = FRICTION.stop + K + stiffness.params.size
        z = ca.SX.sym("z", self.n_z)
        q = ca.SX.sym("q", self.n_q)
        length, ei_r = q[0], q[1]
        c, Q, law = q[2:5], quadric_matrix(q[5:11]), q[FRICTION]
        widths, ps = q[FRICTION.stop:FRICTION.stop + K], q[FRICTION.stop + K:]
        w, nu = z[:nw], z[nw]
        u = z[nw + 1] if mode == "interior" else 1.0
        L = u * length
        # the load point and frame do not depend on κ given w: evaluate the
        # tip with any load, then close the loop through the normal there
        P0 = ca.vertcat(ca.DM.zeros(3), L, ei_r, widths, ps)
        r, frame = rod.tip(w, P0)
        grad = Q @ (r - c)
        normal = grad / ca.norm_2(grad)
        t = friction_vector(law, r, normal)
        t_p = t - ca.dot(t, normal) * normal
        direction = normal + t_p
        P = ca.vertcat(nu * u ** 2 * direction, L, ei_r, widths, ps)
        G = rod.residual(w, P)
        level = ca.dot(r - c, Q @ (r - c)) - 1
        d1 = frame[:, 0]
        along = ca.dot(d1, normal)
        eqs = [G, level] + ([along] if mode == "interior" else [])
        R = ca.vertcat(*eqs)
        self.residual = ca.Function(f"spatial_{mode}", [z, q], [R], ["z", "q"], ["R"])
        force = nu * ei_r / length ** 2 * direction
        #: (z, q) -> r (3), N, L, level, d1·n, normal (3), force on the finger (3),
        #: d1 (3), tangential friction per unit normal force t_p (3); max |R|
        self.post = ca.Function(
            f"spatial_{mode}_post", [z, q],
            [ca.vertcat(r, nu * ei_r / length ** 2, L, level, along, normal, force, d1, t_p),
             ca.mmax(ca.fabs(R))])
        self.shape = ca.Function(f"spatial_{mode}_shape", [z, q], rod.shape(w, P))
        # implicit-function sensitivities: dR/dz, dR/d(c, Q), d(r, L)/dz (dense,
        # for design.solvers.buffers)
        self.sensitivity = ca.Function(
            f"spatial_{mode}_sens", [z, q],
            [ca.densify(m) for m in (ca.jacobian(R, z), ca.jacobian(R, q[QUADRIC]),
                                     ca.jacobian(ca.vertcat(r, L), z))])
        # dense LU: the load's direction follows the normal at r(L), which
        # depends on every node's quaternion, so the Jacobian is over a third
        # full, where LAPACK's dense LU beats a sparse factorisation
        self._newton = NewtonCache(
            f"spatial_{mode}_newton", self.residual, "lapacklu",
            lambda: compiled_jacobian(self.residual, f"{self.residual.name()}_jac_z"))

    @cached_property
    def chord(self) -> Chord:
        """The chord method on this mode's residual (design.solvers.newton.Chord)."""
        return Chord(self.residual)

    def rootfinder(self, tolerance: float = 1e-12, max_iter: int = 30,
                   error_on_fail: bool = False, compiled_jacobian: bool = False
                   ) -> ca.Function:
        """Newton on R(z, q) = 0: (z0, q) -> z (cached; design.solvers.newton).
        ``compiled_jacobian``: its Jacobian compiled, faster per evaluation
        after seconds of gcc per mode once (an empty cache): for the
        optimiser's hundreds of thousands of solves (a simulation's
        continuation steps use :attr:`chord` instead)."""
        return self._newton.get(tolerance, max_iter, error_on_fail, compiled_jacobian)


_CACHE: dict[tuple, SpatialContactTranscription] = {}


def spatial_transcription(stiffness: RodStiffness, intervals: int, degree: int, mode: str
                          ) -> SpatialContactTranscription:
    key = (stiffness.symbolic_key(), intervals, degree, mode)
    if key not in _CACHE:
        _CACHE[key] = SpatialContactTranscription(stiffness, intervals, degree, mode)
    return _CACHE[key]
