"""An independent reference for a finger against an ellipse (the planar model).

Two steps, neither shared with :mod:`design.solvers.contact`:

1. *Least energy*: the finger as N rigid links with bending springs,
   minimising the elastic energy ∫ M²/(2 EI) ds with every node outside the
   ellipse (Ipopt from a bent start). Without friction an equilibrium
   against a rigid object is a constrained minimum of this energy, so this
   finds it with no contact model at all, to O(L/N) in position.
2. *Boundary-value refinement*: the elastica to the contact point (scipy's
   ``solve_bvp``) with the contact conditions as boundary conditions and the
   arc length, force and direction as unknown parameters, started from
   step 1; friction (the force along n + τµ t_c, eq. 3.7) is then switched
   on in steps. Its error is set by ``BVP_TOL``.

Units: m, N, rad; finger frame (base at the origin, unloaded along +x).
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np
from scipy.integrate import solve_bvp

from design.physics.beam import Finger
from design.physics.ellipse import Ellipse

#: solve_bvp's relative residual tolerance (the collocation residual of the
#: dimensionless elastica, whose state is O(1))
BVP_TOL = 1e-8
#: links of the least-energy finger
LINKS = 60
_NLP: dict = {}


@dataclass(frozen=True)
class Reference:
    """A reference contact: load point (m), arc length (m), force on the
    finger (N) and its direction α (rad), slope at the contact (rad), whether
    the tip touches, and the side (+1: the finger deflected to +y)."""

    point: tuple[float, float]
    arc_length: float
    force: float
    alpha: float
    psi: float
    tip_contact: bool
    side: int


def least_energy(finger: Finger, ell: Ellipse, side: int, bend: float):
    """Link angles (N,) of a constrained energy minimum, or None if Ipopt
    fails; the start bends the finger to ``side`` by ``bend`` rad within
    its first quarter."""
    L, n = finger.length, LINKS
    key = (id(finger), n)
    if key not in _NLP:
        h = L / n
        th, q = ca.SX.sym("th", n), ca.SX.sym("q", 5)
        ei = finger.stiffness.ei(np.arange(n) * h)
        cell = np.full(n, h)
        cell[0] = h / 2                              # the clamp's half cell
        energy = ca.sum1(ei * (th - ca.vertcat(0, th[:-1])) ** 2 / (2 * cell))
        x, y = ca.cumsum(h * ca.cos(th)), ca.cumsum(h * ca.sin(th))
        c, s = ca.cos(q[2]), ca.sin(q[2])
        u, v = c * (x - q[0]) + s * (y - q[1]), -s * (x - q[0]) + c * (y - q[1])
        outside = (u / q[3]) ** 2 + (v / q[4]) ** 2 - 1
        _NLP[key] = ca.nlpsol("least_energy", "ipopt",
                              {"x": th, "p": q, "f": energy * L / ei[0], "g": outside},
                              {"ipopt.print_level": 0, "print_time": False,
                               "ipopt.sb": "yes", "ipopt.tol": 1e-8})
    nlp = _NLP[key]
    s = (np.arange(n) + 0.5) * L / n
    out = nlp(x0=side * bend * np.minimum(4 * s / L, 1.0), p=ell.params, lbg=0.0, ubg=np.inf)
    return np.asarray(out["x"]).ravel() if nlp.stats()["success"] else None


def _guess(finger: Finger, ell: Ellipse, th: np.ndarray):
    """The least-energy shape up to its contact node, as a BVP start: mesh u,
    state (X, Y, ψ, μ), parameters (σ, κ, α), tip contact."""
    L, n = finger.length, th.size
    h = L / n
    x, y = np.cumsum(h * np.cos(th)), np.cumsum(h * np.sin(th))
    j = int(np.argmin(ell.level(x, y)))              # the node on the surface
    tip = j == n - 1
    psi = np.concatenate([[0.0], th[:j + 1]])
    X = np.concatenate([[0.0], x[:j + 1]]) / L
    Y = np.concatenate([[0.0], y[:j + 1]]) / L
    g = ell.gradient(x[j], y[j])
    normal = g / np.hypot(*g)
    alpha = float(np.arctan2(normal[1], -normal[0]))
    ei_r = finger.stiffness.compliance_equivalent(L)
    # base moment M(0) = F (x_c sin α + y_c cos α) gives F
    m0 = finger.stiffness.ei(0.0) * th[0] / (h / 2)
    lever = x[j] * np.sin(alpha) + y[j] * np.cos(alpha)
    kappa = max(m0 / lever, 1e-6) * L ** 2 / ei_r if lever > 0 else 1e-3
    u = np.linspace(0.0, 1.0, j + 2)
    mu = np.gradient(psi, u) / ((j + 1) * h) * finger.stiffness.ei(u * (j + 1) * h) * L / ei_r
    return u, np.vstack([X, Y, psi, mu]), np.array([(j + 1) * h / L, kappa, alpha]), tip


def _solve(finger: Finger, ell: Ellipse, tau_mu: float, u, state, p, tip: bool):
    """solve_bvp of the contact (interior, or at the tip), None if it fails."""
    L = finger.length
    ei_r = finger.stiffness.compliance_equivalent(L)

    def split(p):
        return (1.0, p[0], p[1]) if tip else (p[0], p[1], p[2])

    def rhs(u, y, p):
        sigma, kappa, alpha = split(p)
        e = ei_r / finger.stiffness.ei(u * sigma * L)
        return sigma * np.vstack([np.cos(y[2]), np.sin(y[2]), y[3] * e,
                                  -kappa * np.sin(y[2] + alpha)])

    def bc(ya, yb, p):
        _, _, alpha = split(p)
        x, y, psi = yb[0] * L, yb[1] * L, yb[2]
        g = ell.gradient(x, y)
        n = g / np.hypot(*g)
        t_f = np.array([np.cos(psi), np.sin(psi)])
        along = t_f @ n
        t_c = t_f if not tip else (t_f - along * n) / np.hypot(*(t_f - along * n))
        e = n + tau_mu * t_c
        d = np.array([-np.cos(alpha), np.sin(alpha)])
        out = [ya[0], ya[1], ya[2], yb[3], float(ell.level(x, y)),
               (d[0] * e[1] - d[1] * e[0]) / np.hypot(*e)]
        if not tip:
            out.append(along)
        return np.array(out)

    sol = solve_bvp(rhs, bc, u, state, p[1:] if tip else p, tol=BVP_TOL, max_nodes=20000)
    return sol if sol.status == 0 else None


def reference(finger: Finger, ell: Ellipse, friction: float, side: int,
              bends=(0.3, 2.0, 3.0)) -> Reference | None:
    """The least-energy equilibrium on ``side`` (+1 push, -1 pull), refined,
    with friction ratio τµ = ``friction`` (on the finger, towards its tip).
    The constrained minimum from a start bent by the first of ``bends``
    (rad) whose contact is on ``side``; None when none is."""
    for bend in bends:
        th = least_energy(finger, ell, side, bend)
        if th is None:
            continue
        u, state, p, tip = _guess(finger, ell, th)
        done, todo = 0.0, friction
        while True:
            sol = _solve(finger, ell, todo, u, state, p, tip)
            if sol is None:
                if todo - done < 1e-3:
                    break
                todo = 0.5 * (done + todo)            # friction in smaller steps
                continue
            u, state = sol.x, sol.y
            p = np.concatenate([[1.0], sol.p]) if tip else sol.p
            if not tip and p[0] > 1.0:                # the contact passed the tip
                tip = True
                continue
            if todo == friction:
                ref = _reference(finger, ell, u, state, p, tip)
                if ref.side == side:
                    return ref
                break
            done, todo = todo, friction
    return None


def _reference(finger, ell, u, state, p, tip) -> Reference:
    L = finger.length
    ei_r = finger.stiffness.compliance_equivalent(L)
    sigma, kappa, alpha = p
    force, x, y, psi = kappa * ei_r / L ** 2, state[0, -1] * L, state[1, -1] * L, state[2, -1]
    if force < 0:                                   # F < 0 at α is F > 0 at α + π
        force, alpha = -force, alpha + np.pi
    g = ell.gradient(x, y)
    side = 1 if (-np.sin(psi) * g[0] + np.cos(psi) * g[1]) > 0 else -1
    return Reference((float(x), float(y)), float(sigma * L), float(force),
                     float((alpha + np.pi) % (2 * np.pi) - np.pi), float(psi), tip, side)
