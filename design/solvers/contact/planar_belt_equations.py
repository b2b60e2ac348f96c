"""A planar finger touching the belt, alone or with the bird: the equations.

The planar finger (the thesis's, design/solvers/contact/equations.py) is
rigid out of its bending plane. The belt's surface cuts that plane in a
line, n·p = e (n the in-plane unit normal pointing out of the belt, the
in-plane part of the world's Z; e in m); the finger reaches it with its
tip. The belt pushes the tip along n and drags it along the line with
regularised Coulomb friction against the tip's sliding,

    t_p = -µ w / sqrt(w² + ε²) t,   w = (a + G p)·t,

t the line's direction and a + G p the rigid finger's in-plane velocity
over the belt (affine in p). The bird's force is the bird-only equations':
magnitude κ (κ = F l² / EI_r) and direction α, along n + τµ t_c.

Modes (as :mod:`design.solvers.contact.spatial_belt_equations`): ``belt``,
``tip+belt`` and ``interior+belt``, the last as two beam segments
(:class:`~design.solvers.beam.collocation.BeamTranscription`,
``segment=True``): [0, L] under both forces with the tip force's moment
about p(L) at its end, and [L, l] clamped at the first one's end angle
under the tip force alone.

Unknowns z: the beam (one segment over [0, l], or the two), then κ_b and
α_b (not in ``belt``), u = L / l (``interior+belt``), and the belt's
normal load ν_p = N_p l² / EI_r.

Parameters q = [l, EI_r, conic (cx, cy, B00, B01, B11), τµ, line (n (2),
e), belt law (µ, ε, a (2), G (4, row-major)), h_1..h_K, g_1..g_K2,
stiffness...].

Post: the bird-only modes' 12 values (x, y, ψ at the bird's contact, F_b,
α_b, L, level, t_f·n, push, t_c (2), side; zero in ``belt`` but L = l),
then the tip x, y, N_p, the tip's height above the belt, t_f·n at the tip
and the belt's force on the finger (2).
"""

from __future__ import annotations

from functools import cached_property

import casadi as ca

from design.physics.ellipse import gradient_conic, level_conic
from design.physics.stiffness import Stiffness
from design.solvers.beam.collocation import transcription
from design.solvers.contact.spatial_belt_equations import OVERHANG_INTERVALS
from design.solvers.newton import Chord, NewtonCache, compiled_jacobian

#: index of the conic, the bird's signed friction, the belt's line and its law in q
CONIC = slice(2, 7)
TAU_MU = 7
LINE = slice(8, 11)
BELT_LAW = slice(11, 19)
#: post layout beyond the bird's 12
POST_TIP = slice(12, 14)
POST_BELT_FORCE = 14
POST_BELT_LEVEL = 15
POST_BELT_ON_FINGER = slice(17, 19)


def _rotate(angle, v):
    c, s = ca.cos(angle), ca.sin(angle)
    return ca.vertcat(c * v[0] - s * v[1], s * v[0] + c * v[1])


def _cross(a, b):
    return a[0] * b[1] - a[1] * b[0]


class PlanarBeltTranscription:
    """Residual R(z, q), post and shape of one belt mode of the planar finger.

    Attributes
    ----------
    n_z, n_q : int
    residual, post, shape : casadi.Function
        ``shape``: (z, q) -> the finger's points (2, n), base to tip (m),
        and its unit tangents there (2, n).
    """

    def __init__(self, stiffness: Stiffness, intervals: int, degree: int, mode: str):
        self.mode = mode
        name = "planar_belt_" + mode.replace("+belt", "_belt")
        two = mode == "interior+belt"
        bird = mode != "belt"
        self.beam = beam = transcription(stiffness, intervals, degree, segment=True)
        self.overhang = over = transcription(stiffness, OVERHANG_INTERVALS, degree,
                                             segment=True) if two else None
        K, K2, nw = beam.K, OVERHANG_INTERVALS, beam.n_w
        self.n_z = nw + (over.n_w if two else 0) + (2 if bird else 0) + int(two) + 1
        self.n_q = BELT_LAW.stop + K + K2 + stiffness.params.size
        z = ca.SX.sym("z", self.n_z)
        q = ca.SX.sym("q", self.n_q)
        length, ei_r, conic, tau_mu = q[0], q[1], q[CONIC], q[TAU_MU]
        n_p, e_p = q[LINE][:2], q[LINE][2]
        law = q[BELT_LAW]
        widths = q[BELT_LAW.stop:BELT_LAW.stop + K]
        widths2 = q[BELT_LAW.stop + K:BELT_LAW.stop + K + K2]
        ps = q[BELT_LAW.stop + K + K2:]
        w = z[:nw]
        k = nw
        if two:
            w2 = z[k:k + over.n_w]
            k += over.n_w
        kappa_b, alpha_b = (z[k], z[k + 1]) if bird else (0.0, 0.0)
        u = z[-2] if two else 1.0
        nu_p = z[-1]
        L = u * length
        scale = ei_r / length ** 2
        if two:
            L2 = length - L
            end = beam.tip(w, ca.vertcat(0.0, 0.0, L, ei_r, widths, ps, 0.0, 0.0))
            local = over.tip(w2, ca.vertcat(0.0, 0.0, L2, ei_r, widths2, ps, L, 0.0))
            r_b, psi_b = end[:2], end[2]
            r_t, psi_t = r_b + _rotate(psi_b, local[:2]), psi_b + local[2]
        else:
            end = beam.tip(w, ca.vertcat(0.0, 0.0, length, ei_r, widths, ps, 0.0, 0.0))
            r_t, psi_t = end[:2], end[2]
            r_b, psi_b = r_t, psi_t
        # the belt: normal plus regularised sliding friction along its line
        line = ca.vertcat(-n_p[1], n_p[0])
        mu, eps, a, G = law[0], law[1], law[2:4], ca.reshape(law[4:8], 2, 2).T
        sliding = ca.dot(a + G @ r_t, line)
        f_p = nu_p * scale * (n_p - mu * sliding / ca.sqrt(sliding ** 2 + eps ** 2) * line)
        eqs = []
        t_f = ca.vertcat(ca.cos(psi_b), ca.sin(psi_b))
        if bird:
            grad = gradient_conic(r_b[0], r_b[1], conic)
            n_b = grad / ca.norm_2(grad)
            along = ca.dot(t_f, n_b)
            t_c = t_f if two else (t_f - along * n_b) / ca.norm_2(t_f - along * n_b)
            e = n_b + tau_mu * t_c
            d = ca.vertcat(-ca.cos(alpha_b), ca.sin(alpha_b))
            f_b = kappa_b * scale * d
            level_b = level_conic(r_b[0], r_b[1], conic)
        else:
            f_b = ca.DM.zeros(2)
        total = f_b + f_p
        if two:
            mu_end = _cross(r_t - r_b, f_p) * L / ei_r
            eqs.append(beam.residual(w, ca.vertcat(total, L, ei_r, widths, ps, 0.0, mu_end)))
            eqs.append(over.residual(w2, ca.vertcat(_rotate(-psi_b, f_p), L2, ei_r, widths2, ps,
                                                    L, 0.0)))
        else:
            eqs.append(beam.residual(w, ca.vertcat(total, length, ei_r, widths, ps, 0.0, 0.0)))
        if bird:
            eqs.append(level_b)
            if two:
                eqs.append(along)
            eqs.append(_cross(d, e) / ca.norm_2(e))
        level_p = ca.dot(n_p, r_t) - e_p
        eqs.append(level_p)
        R = ca.vertcat(*eqs)
        self.residual = ca.Function(name, [z, q], [R], ["z", "q"], ["R"])
        if bird:
            n_f = ca.vertcat(-ca.sin(psi_b), ca.cos(psi_b))
            bird_post = ca.vertcat(r_b, psi_b, kappa_b * scale, alpha_b, L, level_b, along,
                                   ca.dot(d, e) / ca.norm_2(e), t_c, ca.dot(n_b, n_f))
        else:
            bird_post = ca.vertcat(0.0, 0.0, 0.0, 0.0, 0.0, L, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
        t_tip = ca.vertcat(ca.cos(psi_t), ca.sin(psi_t))
        self.post = ca.Function(
            f"{name}_post", [z, q],
            [ca.vertcat(bird_post, r_t, ca.dot(f_p, n_p), level_p, ca.dot(t_tip, n_p), f_p),
             ca.mmax(ca.fabs(R))])
        if two:
            _, x1, y1, a1, _ = beam.shape(w, ca.vertcat(0.0, 0.0, L, ei_r, widths, ps, 0.0, 0.0))
            _, x2, y2, a2, _ = over.shape(w2, ca.vertcat(0.0, 0.0, L2, ei_r, widths2, ps, L, 0.0))
            c, s = ca.cos(psi_b), ca.sin(psi_b)
            pts = ca.horzcat(ca.horzcat(x1, y1).T,
                             ca.horzcat(r_b[0] + c * x2[1:] - s * y2[1:],
                                        r_b[1] + s * x2[1:] + c * y2[1:]).T)
            slopes = ca.vertcat(a1, psi_b + a2[1:])
        else:
            _, x1, y1, slopes, _ = beam.shape(w, ca.vertcat(0.0, 0.0, length, ei_r, widths, ps,
                                                            0.0, 0.0))
            pts = ca.horzcat(x1, y1).T
        self.shape = ca.Function(f"{name}_shape", [z, q],
                                 [pts, ca.horzcat(ca.cos(slopes), ca.sin(slopes)).T])
        self._newton = NewtonCache(
            f"{name}_newton", self.residual, "qr",
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


_CACHE: dict[tuple, PlanarBeltTranscription] = {}


def planar_belt_transcription(stiffness: Stiffness, intervals: int, degree: int, mode: str
                              ) -> PlanarBeltTranscription:
    key = (stiffness.symbolic_key(), intervals, degree, mode)
    if key not in _CACHE:
        _CACHE[key] = PlanarBeltTranscription(stiffness, intervals, degree, mode)
    return _CACHE[key]
