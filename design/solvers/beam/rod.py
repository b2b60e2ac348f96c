"""Legendre-Gauss collocation of the spatial rod (design/physics/rod.py) in CasADi.

The same transcription as the planar elastica's
(:mod:`design.solvers.beam.collocation`), for the rod's seven states: the
quaternion q (4) and the non-dimensional internal moment μ = m L / EI_r
(3) at each interval start and collocation point, on u = s/L in [0, 1],
with the position ρ = r/L = ∫ d1 du by the same quadrature. Gauss
collocation keeps |q| = 1 exactly (a quadratic invariant of q' = ½ q ⊗ k).

Parameters P = [κ (3), L, EI_r, h_1..h_K, p_EI..., p_EIout..., p_GJ...]:
the load κ = F L² / EI_r in the finger frame, the loaded length, the
reference rigidity, the interval widths (summing to 1) and the three
stiffness profiles' parameters.

A *segment* (``segment=True``) is the part of a finger from arc length s0
to s0 + L, clamped in its own frame at its start, with a point moment at its
end as well as the force: P then ends with [s0, μ_end (3)], μ_end = M L /
EI_r, and μ(1) = μ_end. Two segments make a finger loaded at two points
(design/solvers/contact/spatial_belt_equations.py).
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from design.physics.beam import Finger
from design.physics.rod import quaternion_rotation, rod_rates
from design.physics.stiffness import Stiffness
from design.solvers.beam.collocation import legendre_tables

#: states per node: quaternion (4), moment (3)
N_STATE = 7


@dataclass(frozen=True)
class RodStiffness:
    """The three rigidities of a finger's section against arc length (N m²):
    bending towards y (``soft``, the planar model's EI), towards z
    (``stiff``) and twist (``torsion``, GJ)."""

    soft: Stiffness
    stiff: Stiffness
    torsion: Stiffness

    @classmethod
    def of(cls, finger: Finger) -> "RodStiffness":
        return cls(finger.stiffness, finger.stiffness_out, finger.torsion_rigidity)

    @property
    def parts(self) -> tuple[Stiffness, Stiffness, Stiffness]:
        return self.soft, self.stiff, self.torsion

    @property
    def params(self) -> np.ndarray:
        return np.concatenate([p.params for p in self.parts])

    def symbolic_key(self) -> tuple:
        return tuple(p.symbolic_key() for p in self.parts) + \
            tuple(p.params.size for p in self.parts)

    def casadi(self, s, p) -> list:
        """[GJ, EI_out, EI] at s as CasADi expressions of the stacked parameters p."""
        out, i = [], 0
        for part in self.parts:
            n = part.params.size
            out.append(part.ei_casadi(s, p[i:i + n]))
            i += n
        return out[::-1]


class RodTranscription:
    """Collocation equations of one finger as a spatial rod (CasADi SX).

    Attributes
    ----------
    n_w : int
        Unknowns, 7 K (d+1): (q, μ) at each interval start and collocation
        point, interval by interval.
    n_p : int
        Length of P.
    residual : casadi.Function
        (w, P) -> G, all O(1).
    tip : casadi.Function
        (w, P) -> load point r (3, m) and material frame (3, 3) there.
    shape : casadi.Function
        (w, P) -> s (m), r (3 x n, m), m (3 x n, N m) at the nodes.
    """

    def __init__(self, stiffness: RodStiffness, intervals: int, degree: int = 4,
                 segment: bool = False):
        self.K, self.d = int(intervals), int(degree)
        tau, C, D, B, A = legendre_tables(self.d)
        K, d = self.K, self.d
        self.tau = tau
        self.n_w = N_STATE * K * (d + 1)
        n_stiff = stiffness.params.size
        self.n_p = 5 + K + n_stiff + (4 if segment else 0)
        w = ca.SX.sym("w", self.n_w)
        P = ca.SX.sym("P", self.n_p)
        kappa, L, ei_r = P[0:3], P[3], P[4]
        widths, ps = P[5:5 + K], P[5 + K:5 + K + n_stiff]
        start, mu_end = (P[5 + K + n_stiff], P[6 + K + n_stiff:]) if segment else (0.0, None)
        Z = ca.reshape(w, N_STATE, K * (d + 1))
        scale = ca.sqrt(1 + ca.dot(kappa, kappa))     # smooth at κ = 0, ~1 + |κ|
        res = []
        s_nodes, r_nodes, mu_nodes = [], [], []
        u0, r0 = 0, ca.DM.zeros(3)
        for j in range(K):
            h = widths[j]
            cols = [Z[:, j * (d + 1) + r] for r in range(d + 1)]
            if j == 0:
                res.append(cols[0][:4] - ca.DM([1, 0, 0, 0]))       # q(0) = 1
            tangents = []
            for k in range(1, d + 1):
                u = u0 + tau[k] * h
                s = L * u if mu_end is None else start + L * u
                ratios = ca.vertcat(*[ei_r / v for v in stiffness.casadi(s, ps)])
                q_dot, mu_dot, d1 = rod_rates(cols[k][:4], cols[k][4:], kappa, ratios)
                zp = sum(C[r, k] * cols[r] for r in range(d + 1))
                res.append((zp / h - ca.vertcat(q_dot, mu_dot)) / scale)
                tangents.append(d1)
            end = sum(D[r] * cols[r] for r in range(d + 1))
            if j < K - 1:
                res.append(Z[:, (j + 1) * (d + 1)] - end)            # continuity
            else:
                res.append(end[4:] if mu_end is None else end[4:] - mu_end)  # μ(1) = μ_end
            s_nodes.append(u0)
            r_nodes.append(r0)
            mu_nodes.append(cols[0][4:])
            for k in range(d):
                s_nodes.append(u0 + tau[k + 1] * h)
                r_nodes.append(r0 + h * sum(A[k, r] * tangents[r] for r in range(d)))
                mu_nodes.append(cols[k + 1][4:])
            r0 = r0 + h * sum(B[r] * tangents[r] for r in range(d))
            u0 = u0 + h
        s_nodes.append(u0)
        r_nodes.append(r0)
        mu_nodes.append(end[4:])
        frame = quaternion_rotation(end[:4])
        name = "rod_segment" if segment else "rod"
        self.residual = ca.Function(f"{name}_residual", [w, P], [ca.vertcat(*res)], ["w", "P"], ["G"])
        self.tip = ca.Function(f"{name}_tip", [w, P], [L * r0, frame], ["w", "P"], ["r", "frame"])
        self.shape = ca.Function(f"{name}_shape", [w, P],
                                 [L * ca.vertcat(*s_nodes), L * ca.horzcat(*r_nodes),
                                  ei_r / L * ca.horzcat(*mu_nodes)],
                                 ["w", "P"], ["s", "r", "m"])

    def straight(self) -> np.ndarray:
        """Unknowns of the unloaded, straight rod."""
        z = np.zeros((N_STATE, self.n_w // N_STATE))
        z[0] = 1.0
        return z.T.ravel()

    def parameters(self, force: np.ndarray, at: float, ei_ref: float, widths: np.ndarray,
                   stiffness: RodStiffness) -> np.ndarray:
        """Numeric P for a force (3, N, finger frame) at arc length ``at`` (m)."""
        kappa = np.asarray(force, float) * at ** 2 / ei_ref
        return np.concatenate([kappa, [at, ei_ref], widths, stiffness.params])


_CACHE: dict[tuple, RodTranscription] = {}


def rod_transcription(stiffness: RodStiffness, intervals: int, degree: int = 4,
                      segment: bool = False) -> RodTranscription:
    """Shared :class:`RodTranscription` for this stiffness structure and mesh."""
    key = (stiffness.symbolic_key(), int(intervals), int(degree), bool(segment))
    if key not in _CACHE:
        _CACHE[key] = RodTranscription(stiffness, intervals, degree, segment)
    return _CACHE[key]


@dataclass(frozen=True)
class RodSolution:
    """Equilibrium of a rod under a point force: the load point ``tip`` (3,, m)
    and material frame there (3, 3), the node arc lengths (m), positions
    (3, n, m) and internal moments (3, n, N m), all in the finger frame."""

    tip: np.ndarray
    frame: np.ndarray
    s: np.ndarray
    r: np.ndarray
    moment: np.ndarray
    converged: bool
    residual: float


def solve_rod(finger: Finger, force: np.ndarray, at: float, intervals: int = 8,
              degree: int = 4, steps: int = 8, tolerance: float = 1e-12) -> RodSolution:
    """The rod under a point force (3,, N, finger frame) at arc length ``at``,
    by Newton continuation from the unloaded rod in ``steps`` equal load
    increments (the branch continued from F = 0)."""
    stiffness = RodStiffness.of(finger)
    tr = rod_transcription(stiffness, intervals, degree)
    rf = ca.rootfinder("rod_newton", "newton", tr.residual,
                       {"abstol": tolerance, "max_iter": 50, "line_search": True,
                        "linear_solver": "csparse", "error_on_fail": False})
    ei_ref = finger.stiffness.compliance_equivalent(at)
    widths = np.full(tr.K, 1.0 / tr.K)
    w = tr.straight()
    ok = True
    for lam in np.linspace(1.0 / steps, 1.0, steps):
        P = tr.parameters(lam * np.asarray(force, float), at, ei_ref, widths, stiffness)
        w = np.asarray(rf(w, P)).ravel()
        ok = ok and bool(rf.stats().get("success", False))
    G = float(np.max(np.abs(np.asarray(tr.residual(w, P)))))
    tip, frame = (np.asarray(v) for v in tr.tip(w, P))
    s, r, m = (np.asarray(v) for v in tr.shape(w, P))
    return RodSolution(tip.ravel(), frame, s.ravel(), r, m, ok and G < 1e-9, G)
