"""Finger-against-ellipse contact equations in CasADi (MODEL.md §3, thesis §3.1).

Unknowns, in the finger frame: the collocated beam w on [0, L] (see
:class:`~design.solvers.beam.collocation.BeamTranscription`), the load
κ = F L_ref² / EI_r (L_ref the finger length), the force direction α and,
for contact inside the span, u = L / l. Equations, all dimensionless:

* the beam, G(w; F, α, L) = 0;
* the contact point (the load point) lies on the ellipse, f(x_L, y_L) = 0;
* *interior* contact: the finger is tangent there, t_f · n = 0 (eq. 3.8);
  *tip* contact: L = l and the tip slides on the surface (no tangency);
* the force on the finger points along n + τ µ t_c (eq. 3.7): n is the
  object's outward normal, t_c the sliding tangent (the finger's tangent,
  or for tip contact the surface's tangent oriented like the finger), and
  τ = +1 puts the friction on the finger towards its tip (the thesis's
  convention), τ = -1 towards its base. Only the product τ µ enters, so
  friction can be continued smoothly through zero.

The force sign is not imposed: a solution is physical when κ ≥ 0 and the
force pushes the finger away from the object (checked by the solver).

Parameters q = [l, EI_r, cx, cy, θ, a, b, τµ, h_1..h_K, p...]: finger
length, reference rigidity, the ellipse in the finger frame, the signed
friction coefficient, the beam mesh and the stiffness parameters. With
``ellipse="conic"`` the ellipse is q[2:7] = [cx, cy, B00, B01, B11]
((p - c)ᵀ B (p - c) = 1): smooth in the bird's pose even where the cut is a
circle and its axes are undefined (the optimiser's choice).
"""

from __future__ import annotations

from functools import cached_property

import casadi as ca
import numpy as np

from design.physics.ellipse import (Ellipse, gradient_casadi, gradient_conic, level_casadi,
                                    level_conic)
from design.physics.stiffness import Stiffness
from design.solvers.beam.collocation import transcription
from design.solvers.compiled import compiled
from design.solvers.newton import Chord, NewtonCache, compiled_jacobian

MODES = ("interior", "tip")
#: ellipse parameterisations: (level, gradient) functions of (x, y, q[ELLIPSE])
ELLIPSE_FORMS = {"axes": (level_casadi, gradient_casadi), "conic": (level_conic, gradient_conic)}
#: index of the ellipse parameters (cx, cy, θ, a, b) in q
ELLIPSE = slice(2, 7)
#: index of the signed friction coefficient τµ in q
FRICTION = 7


class ContactTranscription:
    """Residual R(z, q) and helpers for one contact mode.

    Attributes
    ----------
    beam : BeamTranscription
    n_z, n_q : int
        Sizes of the unknown and parameter vectors.
    residual, rootfinder, post, sensitivity : casadi.Function
    """

    def __init__(self, stiffness: Stiffness, intervals: int, degree: int, mode: str,
                 ellipse: str = "axes"):
        self.mode, self.ellipse = mode, ellipse
        level, gradient = ELLIPSE_FORMS[ellipse]
        self.beam = beam = transcription(stiffness, intervals, degree)
        K, nw = beam.K, beam.n_w
        self.n_z = nw + (3 if mode == "interior" else 2)
        self.n_q = 8 + K + stiffness.params.size
        z = ca.SX.sym("z", self.n_z)
        q = ca.SX.sym("q", self.n_q)
        length, ei_r, ell, tau_mu = q[0], q[1], q[ELLIPSE], q[FRICTION]
        widths, ps = q[8:8 + K], q[8 + K:]
        w, kappa, alpha = z[:nw], z[nw], z[nw + 1]
        u = z[nw + 2] if mode == "interior" else 1.0
        L = u * length
        force = kappa * ei_r / length ** 2
        P = ca.vertcat(force, alpha, L, ei_r, widths, ps)
        G = beam.residual(w, P)
        tip = beam.tip(w, P)
        x, y, psi = tip[0], tip[1], tip[2]
        grad = gradient(x, y, ell)
        normal = grad / ca.norm_2(grad)
        t_f = ca.vertcat(ca.cos(psi), ca.sin(psi))
        along = ca.dot(t_f, normal)
        if mode == "interior":
            t_c = t_f
        else:
            t_c = t_f - along * normal
            t_c = t_c / ca.norm_2(t_c)
        e = normal + tau_mu * t_c
        d = ca.vertcat(-ca.cos(alpha), ca.sin(alpha))
        direction = (d[0] * e[1] - d[1] * e[0]) / ca.norm_2(e)
        eqs = [G, level(x, y, ell)]
        if mode == "interior":
            eqs.append(along)
        eqs.append(direction)
        R = ca.vertcat(*eqs)
        self.residual = ca.Function(f"contact_{mode}", [z, q], [R], ["z", "q"], ["R"])
        n_f = ca.vertcat(-ca.sin(psi), ca.cos(psi))
        #: (z, q) -> load point x, y, ψ; F; α; L; f; t_f·n; push = d·e/|e|; t_c (2);
        #: side = n·n_f (> 0: the object is on the finger's -y side, it pushes it to +y)
        post = ca.vertcat(x, y, psi, force, alpha, L, level(x, y, ell), along,
                          ca.dot(d, e) / ca.norm_2(e), t_c, ca.dot(normal, n_f))
        self.post = ca.Function(f"contact_{mode}_post", [z, q], [post, ca.mmax(ca.fabs(R))])
        self.shape = ca.Function(f"contact_{mode}_shape", [z, q], beam.shape(w, P))
        # implicit-function sensitivities: dR/dz, dR/d(ellipse), d(x_L, y_L, L)/dz,
        # with post's first output (dense, for design.solvers.buffers: reading a
        # 63 x 63 DM into numpy took longer than evaluating it). Interpreted:
        # compiled, it saved 4 % of a grasp scene's time for 2.2 s of gcc per
        # mode on an empty cache
        tip_l = ca.vertcat(x, y, L)
        self.sensitivity = ca.Function(
            f"contact_{mode}_sens", [z, q],
            [ca.densify(ca.jacobian(R, z)), ca.densify(ca.jacobian(R, q[ELLIPSE])),
             ca.densify(ca.jacobian(tip_l, z)), post])
        self._continued: dict = {}
        self._newton = NewtonCache(
            f"contact_{self.mode}_newton", self.residual, "qr",
            lambda: compiled_jacobian(self.residual,
                                      f"{self.residual.name()}_{self.ellipse}_jac_z"))

    @cached_property
    def chord(self) -> Chord:
        """The chord method on this mode's residual (design.solvers.newton.Chord)."""
        return Chord(self.residual)

    def rootfinder(self, tolerance: float = 1e-12, max_iter: int = 40,
                   error_on_fail: bool = False, compiled_jacobian: bool = True
                   ) -> ca.Function:
        """Newton on R(z, q) = 0: (z0, q) -> z (cached; design.solvers.newton),
        its Jacobian compiled (a few seconds once, on an empty cache)."""
        return self._newton.get(tolerance, max_iter, error_on_fail, compiled_jacobian)

    def continued(self, tolerance: float, max_iter: int) -> ca.Function:
        """(z0, q) -> (z, post, max |R|): undamped Newton from z0 (CasADi's
        ``fast_newton``, stopping at max |R| ≤ ``tolerance`` or after
        ``max_iter`` iterations) and :attr:`post` in one function, compiled
        to C where a compiler is (design/solvers/compiled.py), for an
        integrator's many trial solves from a nearby solution (cached). No
        line search: the caller checks the residual and falls back to the
        damped, stepped solve."""
        key = (tolerance, max_iter)
        if key not in self._continued:
            z0, q = ca.MX.sym("z0", self.n_z), ca.MX.sym("q", self.n_q)
            newton = ca.rootfinder(f"contact_{self.mode}_{self.ellipse}_fast_newton",
                                   "fast_newton", self.residual,
                                   {"abstol": tolerance, "max_iter": max_iter})
            z = newton(z0, q)
            f = ca.Function(f"contact_{self.mode}_{self.ellipse}_continued", [z0, q],
                            [z, *self.post(z, q)])
            self._continued[key] = compiled([f]).functions[0]
        return self._continued[key]

    def parameters(self, length: float, ei_ref: float, ellipse: Ellipse, tau_mu: float,
                   widths: np.ndarray, stiffness: Stiffness) -> np.ndarray:
        return np.concatenate([[length, ei_ref], ellipse.params, [tau_mu], widths,
                               stiffness.params])


_CACHE: dict[tuple, ContactTranscription] = {}


def contact_transcription(stiffness: Stiffness, intervals: int, degree: int,
                          mode: str, ellipse: str = "axes") -> ContactTranscription:
    """Shared transcription for this stiffness structure, mesh, mode and
    ellipse form."""
    key = (stiffness.symbolic_key(), intervals, degree, mode, ellipse)
    if key not in _CACHE:
        _CACHE[key] = ContactTranscription(stiffness, intervals, degree, mode, ellipse)
    return _CACHE[key]
