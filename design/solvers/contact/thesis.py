"""The thesis's two contact algorithms, kept as baselines (thesis §3.2-3.4).

Both solve the push case (finger deflected to +y_f; pull is solved on the
mirrored scene) with friction at the edge of sliding towards the finger's
tip: α + ψ0 = π/2 + atan µ (eq. 3.7).

Algorithm I (Figure 3-2): a uniform finger with an effective EI. From a
contact guess (x_i, y_i) on the ellipse, the surface slope gives ψ0 (eq. 3.8),
friction gives α, Frisch-Fay gives p, ζ (2.10b-c), then k from x_i (2.9a)
and the finger's own y at x_i (2.9b); the guess is moved by
x_i ← x_i + β (y - y_i) until |y - y_i| < ERR. Initial guess: the parabola
y = a x² tangent to the ellipse (eqs. 3.9-3.10). The step β is the user's to
tune (0.6 for Case 1, ≤ 0.05 for Case 2); eq. (3.16)'s adaptive β/tan ψ0 is
an option.

Algorithm II (eqs. 3.12-3.15): the FDM beam (N interior points, thesis
N = 155) and the contact conditions as one Newton system in
X = [w_1..w_{N+1}, L, F, x_i, y_i, α], integrals by Simpson's rule (N odd),
solved by plain Newton from the parabola guess.

They are here so that their failures can be measured, not to be used.
"""

from __future__ import annotations

import casadi as ca
import numpy as np
from scipy import special

from design.physics.beam import Finger
from design.physics.contact import (SIDES, ContactSolution, FingerPose, Motion, no_contact,
                                    segment_overlap)
from design.physics.ellipse import Ellipse, gradient_casadi, level_casadi
from design.solvers.newton import damped_newton

#: Thesis Table 5-2 / Figure 3-4: effective EI (N m^2) of the soft finger
#: (E = 4.8 MPa) against contact position x_f (m)
THESIS_EFFECTIVE_EI = (np.array([0.0508, 0.06604, 0.08128, 0.09653, 0.11176, 0.127]),
                       np.array([0.1108, 0.0915, 0.0786, 0.0694, 0.0627, 0.0506]))


def parabola_guess(ell: Ellipse, length: float) -> tuple[float, float, float] | None:
    """Contact guess from the parabola y = a x² tangent to the ellipse from
    above (eqs. 3.9-3.10): a = max_x y_hi(x)/x², the touching point (x, y)."""
    x_lo, x_hi = ell.x_range()
    lo, hi = max(1e-6 * length, x_lo), min(length, x_hi)
    if lo >= hi:
        return None
    x = np.linspace(lo, hi, 2001)
    _, y_hi, meets = ell.y_range_at(x)
    ratio = np.where(meets, y_hi / x ** 2, -np.inf)
    i = int(np.argmax(ratio))
    return float(x[i]), float(y_hi[i]), float(ratio[i])


def _upper_y(ell: Ellipse, x: float) -> float:
    return float(ell.y_range_at(np.clip(x, *ell.x_range()))[1])


class _Mirrored:
    """Solve push on the scene mirrored about x_f for a pull contact."""

    def _push_frame(self, pose: FingerPose, ellipse: Ellipse, sliding: str):
        ell = pose.view(ellipse)
        side = SIDES.get(sliding, 1)
        return (ell if side > 0 else ell.mirrored()), side

    def _start(self, pose: FingerPose, ellipse: Ellipse, sliding: str):
        """Both algorithms' start: (the ellipse in the push frame, the side,
        the parabola guess (x, y, a) of eq. 3.11), or the solution when the
        straight finger misses or no parabola touches."""
        length = self.finger.length
        ell, side = self._push_frame(pose, ellipse, sliding)
        if segment_overlap(ell, length) >= 0:
            return no_contact(pose, length, "the straight finger misses the object")
        guess = parabola_guess(ell, length)
        if guess is None:
            return no_contact(pose, length, "no parabola touches the object", converged=False)
        return ell, side, guess


class AlgorithmI(_Mirrored):
    """Thesis Algorithm I: Frisch-Fay with an effective EI and a fixed-point step β.

    Parameters
    ----------
    finger : Finger
        A uniform finger uses its EI; a non-uniform one the thesis's
        effective EI table (Figure 3-4) scaled by E / 4.8 MPa.
    friction : float
    step : float
        β of the update x_i ← x_i + β y_error.
    adaptive : bool
        Use β / tan ψ0 (eq. 3.16).
    tolerance : float
        ERR on |y_error| in m (thesis: 0.5 mm).
    """

    name = "thesis-1"

    def __init__(self, finger: Finger, friction: float, step: float = 0.3,
                 adaptive: bool = False, tolerance: float = 5e-4, max_iter: int = 500):
        self.finger, self.mu = finger, float(friction)
        self.step, self.adaptive = step, adaptive
        self.tolerance, self.max_iter = tolerance, max_iter
        stiff = finger.stiffness
        if stiff.uniform:
            self.ei = lambda x: float(stiff.ei(0.0))
        else:
            scale = getattr(stiff, "E", 4.8e6) / 4.8e6
            xs, eis = THESIS_EFFECTIVE_EI
            self.ei = lambda x: scale * float(np.interp(x, xs, eis))

    def solve(self, pose: FingerPose, ellipse: Ellipse, sliding: str = "push",
              motion: Motion | None = None) -> ContactSolution:
        length = self.finger.length
        start = self._start(pose, ellipse, sliding)
        if isinstance(start, ContactSolution):
            return start
        ell, side, guess = start
        x_i, y_i = guess[0], guess[1]
        trace = []
        converged, its, state = False, 0, None
        for its in range(1, self.max_iter + 1):
            g = ell.gradient(x_i, y_i)
            psi0 = float(np.arctan2(-g[0], g[1]))             # slope of the surface (3.8)
            alpha = np.pi / 2 + np.arctan(self.mu) - psi0     # friction (3.7)
            state = _ff_tip(alpha, psi0, x_i)
            if state is None:
                break
            k, y_f, kl = state
            y_err = y_f - y_i
            trace.append((x_i, y_i, y_err))
            if abs(y_err) < self.tolerance:
                converged = True
                break
            beta = self.step / np.tan(psi0) if self.adaptive else self.step
            x_i = float(np.clip(x_i + beta * y_err, *ell.x_range()))
            y_i = _upper_y(ell, x_i)
        if state is None:
            return no_contact(pose, length, "Frisch-Fay has no solution at this contact guess",
                              converged=False)
        k, _, kl = state
        force = k ** 2 * self.ei(x_i)
        arc = kl / k
        msg = "" if converged else f"no convergence in {self.max_iter} iterations (β = {self.step})"
        if arc > length:
            converged, msg = False, f"contact arc length {arc:.4f} m beyond the finger ({length} m)"
        s = np.array([0.0, arc])
        return ContactSolution(
            True, float(force), float(side * alpha), float(arc), (float(x_i), float(side * y_i)),
            float(side * psi0), False, "push" if side > 0 else "pull", "tipward", pose, s,
            np.array([0.0, x_i]), np.array([0.0, side * y_i]), converged, its, msg,
            extras={"trace": trace, "effective_EI": self.ei(x_i)})

    def solve_pass(self, poses, ellipses, sliding="push", motion=None, progress=None):
        return [self.solve(p, e, sliding, motion) for p, e in zip(poses, ellipses)]


def _ff_tip(alpha: float, psi0: float, x_i: float):
    """k, the load point's y, and kL of the Frisch-Fay beam whose load point has
    slope ψ0 under direction α and lies at x = x_i (eqs. 2.9-2.12)."""
    p = np.sin((alpha + psi0) / 2)
    if not 0 < abs(np.sin(alpha / 2)) < abs(p) < 1:
        return None
    m = p * p
    zeta = np.arcsin(np.sin(alpha / 2) / p)
    kl = special.ellipk(m) - special.ellipkinc(zeta, m)
    h = 2 * (special.ellipe(m) - special.ellipeinc(zeta, m)) - kl
    k = (2 * p * np.sin(alpha) * np.cos(zeta) + h * np.cos(alpha)) / x_i
    if k <= 0:
        return None
    y = (2 * p * np.cos(alpha) * np.cos(zeta) - h * np.sin(alpha)) / k
    return float(k), float(y), float(kl)


class AlgorithmII(_Mirrored):
    """Thesis Algorithm II: FDM beam and contact as one plain Newton system.

    Parameters
    ----------
    finger : Finger
    friction : float
    nodes : int
        N interior FDM points (odd, for Simpson's rule; thesis: 155).
    tolerance : float
        Newton stops when the step's max-norm is below this.
    """

    name = "thesis-2"

    def __init__(self, finger: Finger, friction: float, nodes: int = 155,
                 tolerance: float = 1e-10, max_iter: int = 100):
        self.finger, self.mu = finger, float(friction)
        self.nodes = nodes + 1 - nodes % 2           # odd
        self.tolerance, self.max_iter = tolerance, max_iter
        self._system = self._build()

    def _build(self):
        n = self.nodes
        stiff = self.finger.stiffness
        X = ca.SX.sym("X", n + 6)
        q = ca.SX.sym("q", 5)                        # ellipse in the finger frame
        w = X[:n + 1]                                # w_1 .. w_{N+1}
        L, F, xi, yi, alpha = X[n + 1], X[n + 2], X[n + 3], X[n + 4], X[n + 5]
        h = 1.0 / (n + 1)
        wf = ca.vertcat(alpha, w)                    # w_0 .. w_{N+1}
        ds = ca.SX.sym("s")
        ei_expr = stiff.ei_casadi(ds, stiff.params)
        ei_and_slope = ca.Function("ei", [ds], [ei_expr, ca.jacobian(ei_expr, ds)])
        G = []
        for i in range(1, n + 1):
            ei, dei = ei_and_slope(i * h * L)
            d1 = (wf[i + 1] - wf[i - 1]) / (2 * h)
            f = -(L * dei / ei) * d1 - F * L ** 2 / ei * ca.sin(wf[i])
            G.append(wf[i - 1] - 2 * wf[i] + wf[i + 1] - h ** 2 * f)
        G.append(-wf[n - 1] / 3 + 4 * wf[n] / 3 - wf[n + 1])          # α1'(1) = 0 (2.26)
        simpson = np.ones(n + 2)
        simpson[1:-1:2], simpson[2:-1:2] = 4, 2
        weights = ca.DM(simpson * h / 3)
        G.append(xi - L * ca.dot(weights, ca.cos(wf - alpha)))           # (3.13a)
        G.append(yi - L * ca.dot(weights, ca.sin(wf - alpha)))           # (3.13b)
        G.append(level_casadi(xi, yi, q))                                # (3.6)
        G.append(ca.tan(wf[n + 1] - np.pi / 2) - self.mu)               # (3.7)
        g = gradient_casadi(xi, yi, q)
        G.append(-g[0] / g[1] - ca.tan(wf[n + 1] - alpha))               # (3.8)
        R = ca.vertcat(*G)
        return ca.Function("thesis2", [X, q], [R, ca.jacobian(R, X)])

    def solve(self, pose: FingerPose, ellipse: Ellipse, sliding: str = "push",
              motion: Motion | None = None) -> ContactSolution:
        length, n = self.finger.length, self.nodes
        start = self._start(pose, ellipse, sliding)
        if isinstance(start, ContactSolution):
            return start
        ell, side, (x0, y0, a) = start
        # parabola: slope 2 a x; arc length (3.11); force from Frisch-Fay with EI at the base
        psi = np.arctan(2 * a * x0 * np.linspace(0, 1, n + 2))
        arc = float(np.trapezoid(np.sqrt(1 + (2 * a * np.linspace(0, x0, 200)) ** 2),
                                 np.linspace(0, x0, 200)))
        alpha = np.pi / 2 + np.arctan(self.mu) - psi[-1]
        ei0 = float(self.finger.stiffness.compliance_equivalent(arc))
        force = 3 * ei0 * y0 / arc ** 3 / max(np.sin(alpha), 0.1)
        X = np.concatenate([psi[1:] + alpha, [arc, force, x0, y0, alpha]])
        # the thesis's plain Newton: no damping
        def system(X):
            R, J = self._system(X, ell.params)
            return np.asarray(R).ravel(), np.asarray(J)

        res = damped_newton(system, X, self.tolerance, self.max_iter, min_damping=1.0)
        X, converged, its, msg = res.x, res.converged, res.iterations, res.message
        w = X[:n + 1]
        L, F, xi, yi, alpha = X[n + 1:]
        spurious = converged and not (0 < L <= length and F >= 0)
        if spurious:
            converged, msg = False, f"spurious root: L = {L:.4g} m, F = {F:.4g} N"
        u = np.linspace(0, 1, n + 2)
        wf = np.concatenate([[alpha], w])
        xs = L * np.concatenate([[0], np.cumsum((np.cos(wf[1:] - alpha) + np.cos(wf[:-1] - alpha)) / 2 * np.diff(u))])
        ys = L * np.concatenate([[0], np.cumsum((np.sin(wf[1:] - alpha) + np.sin(wf[:-1] - alpha)) / 2 * np.diff(u))])
        return ContactSolution(
            True, float(F), float(side * alpha), float(L), (float(xi), float(side * yi)),
            float(side * (w[-1] - alpha)), False, "push" if side > 0 else "pull", "tipward", pose,
            L * u, xs, side * ys, bool(converged), its, msg)

    def solve_pass(self, poses, ellipses, sliding="push", motion=None, progress=None):
        return [self.solve(p, e, sliding, motion) for p, e in zip(poses, ellipses)]
