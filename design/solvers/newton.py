"""Newton's method, for every nonlinear solve of the toolkit, with a status.

:func:`damped_newton` solves numpy systems (the beam's finite differences
and shooting, the thesis's Algorithm II, the BDF-4 step); :class:`NewtonCache`
builds CasADi rootfinders once per setting (the contact equations inside the
design NLP); :class:`Chord` solves a simulation's contact continuation steps
(Newton, and the chord method on the LU factors Newton leaves).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, NamedTuple

import casadi as ca
import numpy as np
from scipy.linalg import get_lapack_funcs


@dataclass(frozen=True)
class NewtonResult:
    """The last iterate ``x`` with its residual, and whether it converged
    (``message`` says why not)."""

    x: np.ndarray
    residual: np.ndarray
    converged: bool
    iterations: int
    message: str = ""


def damped_newton(fun: Callable[[np.ndarray], tuple[np.ndarray, object]], x0: np.ndarray,
                  tolerance: float, max_iter: int, *,
                  solve: Callable[[object, np.ndarray], np.ndarray] = np.linalg.solve,
                  min_damping: float = 1e-4, relative: bool = False,
                  residual_tolerance: float = 0.0) -> NewtonResult:
    """Solve r(x) = 0 by Newton's method with a backtracking line search.

    Parameters
    ----------
    fun : callable
        ``fun(x) -> (r, J)``: the residual (n,) and its Jacobian in the form
        ``solve`` takes.
    x0 : ndarray, shape (n,)
    tolerance : float
        Converged once the step taken is at most this in max-norm (times
        max(1, max|x|) if ``relative``), or the residual at most
        ``residual_tolerance``.
    max_iter : int
    solve : callable, optional
        ``solve(J, b) -> J⁻¹ b`` (dense by default; e.g. a banded solver);
        a ``LinAlgError`` or ``ValueError`` counts as a singular Jacobian.
    min_damping : float, optional
        Each step x + λ Δx, Δx = -J⁻¹ r, halves λ from 1 until |r| decreases
        (and is finite), or until λ ≤ ``min_damping``, where it is taken
        anyway; 1 gives the plain (undamped) Newton iteration.

    Returns
    -------
    NewtonResult
        Not converged when the Jacobian is singular, the residual turns
        non-finite, or ``max_iter`` iterations do not meet the tolerance.
    """
    x = np.array(x0, dtype=float)
    r, jac = fun(x)
    for it in range(1, max_iter + 1):
        try:
            dx = solve(jac, -r)
        except (np.linalg.LinAlgError, ValueError):
            return NewtonResult(x, r, False, it, "singular Jacobian")
        lam, norm0 = 1.0, np.linalg.norm(r)
        while True:
            x_try = x + lam * dx
            r_try, jac_try = fun(x_try)
            finite = np.all(np.isfinite(r_try))
            if (finite and np.linalg.norm(r_try) < norm0) or lam <= min_damping:
                break
            lam *= 0.5
        if not finite or not np.all(np.isfinite(x_try)):
            return NewtonResult(x_try, r_try, False, it, "Newton diverged (non-finite iterate)")
        x, r, jac = x_try, r_try, jac_try
        scale = max(1.0, float(np.max(np.abs(x)))) if relative else 1.0
        if np.max(np.abs(lam * dx)) <= tolerance * scale or \
                np.max(np.abs(r)) <= residual_tolerance:
            return NewtonResult(x, r, True, it)
    return NewtonResult(x, r, False, max_iter,
                        f"Newton did not converge in {max_iter} iterations")


def forward_difference(residual: Callable[[np.ndarray], np.ndarray], relative_step: float = 1e-7
                       ) -> Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]]:
    """``fun`` for :func:`damped_newton` from a residual alone: its Jacobian by
    forward differences, column j stepped by ``relative_step`` max(1, |x_j|)."""
    def fun(x):
        r = residual(x)
        jac = np.empty((r.size, x.size))
        for j in range(x.size):
            dx = np.zeros_like(x)
            dx[j] = relative_step * max(1.0, abs(x[j]))
            jac[:, j] = (residual(x + dx) - r) / dx[j]
        return r, jac
    return fun


class NewtonCache:
    """CasADi rootfinders (z0, q) -> z of one residual R(z, q) = 0, built once
    per (tolerance, max_iter, error_on_fail): Newton with line search;
    ``error_on_fail`` raises instead of returning the last iterate (inside an
    NLP, where Ipopt then shortens its step). ``jacobian``: a function
    making (z, q) -> (∂R/∂z, R), to use at every Newton step instead of
    CasADi's own (e.g. a compiled one, design/solvers/compiled.py: the same
    operations, so the same iterates), made when the first rootfinder is."""

    def __init__(self, name: str, residual: ca.Function, linear_solver: str,
                 jacobian: Callable[[], ca.Function] | None = None):
        self.name, self.residual, self.linear_solver = name, residual, linear_solver
        self._make_jacobian, self._jacobian = jacobian, None
        self._built: dict = {}

    def get(self, tolerance: float, max_iter: int, error_on_fail: bool,
            use_jacobian: bool = True) -> ca.Function:
        """The rootfinder; ``use_jacobian`` false: with CasADi's own Jacobian
        even when a ``jacobian`` was given (no compiling for it)."""
        key = (tolerance, max_iter, error_on_fail, use_jacobian)
        if key not in self._built:
            opts = {"abstol": tolerance, "max_iter": max_iter, "error_on_fail": error_on_fail,
                    "line_search": True, "linear_solver": self.linear_solver,
                    "show_eval_warnings": False}
            if self._make_jacobian is not None and use_jacobian:
                if self._jacobian is None:
                    self._jacobian = self._make_jacobian()
                opts["jacobian_function"] = self._jacobian
            self._built[key] = ca.rootfinder(self.name, "newton", self.residual, opts)
        return self._built[key]


def implicit_rate(jz: np.ndarray, rhs: np.ndarray) -> np.ndarray:
    """The rates ż of a root of R(z, q) = 0 from jz ż = rhs (the implicit-function
    theorem, rhs = -∂R/∂q q̇): LU, an order of magnitude faster than least
    squares at a contact's size; where jz is singular (a fold), the
    least-squares minimum-norm rates."""
    try:
        return np.linalg.solve(jz, rhs)
    except np.linalg.LinAlgError:
        return np.linalg.lstsq(jz, rhs, rcond=None)[0]


def compiled_jacobian(residual: ca.Function, name: str) -> ca.Function:
    """(z, q) -> (∂R/∂z, R) of an SX residual R(z, q) for the Newton steps,
    compiled when a compiler is there (design/solvers/compiled.py; the same
    operations as CasADi's own, so the same iterates to the last bit)."""
    from design.solvers.compiled import compiled
    z = ca.SX.sym("z", residual.size1_in(0))
    q = ca.SX.sym("q", residual.size1_in(1))
    r = residual(z, q)
    return compiled([ca.Function(name, [z, q], [ca.jacobian(r, z), r])]).functions[0]


class LU(NamedTuple):
    """LU factors of a Jacobian with their row pivots (LAPACK's getrf:
    column-major, 0-based int32 swaps), and the two arrays' addresses (for
    design/solvers/native_chord.py: taking them costs more than its call)."""

    lu: np.ndarray
    piv: np.ndarray
    addresses: tuple[int, int]


class Root(NamedTuple):
    """:meth:`Chord.newton`'s last iterate, the LU factors of the last
    Jacobian it factored (near the root when converged: the chord method's
    to continue from; None when z0 was the root), its iterations and
    whether max |R| met the tolerance."""

    z: np.ndarray
    lu: LU | None
    iterations: int
    converged: bool


#: a Newton step cut by halving at most this many times before the solve
#: gives up: a residual that no cut of the step reduces has no root nearby
#: (a step across a fold), and the caller takes a shorter step
LINE_SEARCH_CUTS = 4
#: Newton keeps an iteration's Jacobian factors for the next while its full
#: step cut max |R| below this fraction of what it was (the simplified Newton
#: method: a Jacobian and its factorisation cost as much as 30-100 compiled
#: residuals); after a weaker step, or one the line search cut, or where the
#: kept factors' step does not reduce max |R|, it factors the Jacobian anew
KEEP_FACTORS_BELOW = 0.1


class Chord:
    """Newton's method and the chord method (Newton with the Jacobian of a
    nearby solution) on one residual R(z, q), for the many short continuation
    steps of a simulation. A chord iteration is one residual evaluation
    (compiled where a compiler is, design/solvers/compiled.py) and one solve
    with the LU factors kept from that solution, instead of a Jacobian and
    its factorisation; it converges linearly, fast while the Jacobian has
    changed little, and the caller falls back to :meth:`newton` where it does
    not converge within the iterations allowed. Both stop at the same
    residual tolerance. The Jacobian is CasADi's, interpreted: the
    thousands of factorisations of a simulation do not repay compiling it."""

    def __init__(self, residual: ca.Function):
        from design.solvers.buffers import Buffered
        from design.solvers.compiled import compiled
        from design.solvers.native_chord import NativeChord, source
        n = residual.size1_in(0)
        done = compiled([residual], source(residual.name(), n))
        self._residual = Buffered(done.functions[0])
        #: the chord loop in C (None: interpreted, the loop in :meth:`solve`)
        self.native = NativeChord(done.library, residual.name(), n, residual.size1_in(1)) \
            if done.compiled else None
        #: chord updates made so far (the cost of :meth:`solve`, one residual
        #: evaluation and one LU solve each)
        self.updates = 0
        z, q = ca.SX.sym("z", n), ca.SX.sym("q", residual.size1_in(1))
        self._jacobian = Buffered(ca.Function(f"{residual.name()}_dense_jz", [z, q],
                                              [ca.densify(ca.jacobian(residual(z, q), z))]))
        self._getrf, self._getrs = get_lapack_funcs(("getrf", "getrs"), (np.zeros(1),))

    def factor(self, z: np.ndarray, q: np.ndarray) -> LU | None:
        """∂R/∂z at (z, q), LU-factored; None where it is singular or not
        finite (e.g. a square root's derivative at 0)."""
        jac = self._jacobian(z, q)[0]
        if not np.all(np.isfinite(jac)):
            return None
        lu, piv, info = self._getrf(jac, overwrite_a=True)
        return LU(lu, piv, (lu.ctypes.data, piv.ctypes.data)) if info == 0 else None

    def lu_solve(self, factor: LU, r: np.ndarray) -> np.ndarray:
        """J⁻¹ r from the LU factors of J."""
        return self._getrs(factor.lu, factor.piv, r)[0]

    def solve(self, z0: np.ndarray, q: np.ndarray, factor: LU, tolerance: float,
              max_iter: int) -> np.ndarray | None:
        """The root from z0 by the chord method with ``factor``, with max |R|
        ≤ ``tolerance``, or None."""
        if self.native is not None:
            z, updates = self.native.solve(z0, q, factor, tolerance, max_iter)
            self.updates += updates
            return z
        z = np.array(z0, float)
        z_in, q_in = self._residual.inputs
        q_in[:] = q
        with np.errstate(over="ignore", invalid="ignore"):   # a diverging chord: None below
            for it in range(max_iter + 1):
                z_in[:] = z
                r = self._residual.run()[0]
                size = np.abs(r).max()
                if size <= tolerance:
                    return z
                if not np.isfinite(size) or it == max_iter:
                    return None
                z -= self._getrs(factor.lu, factor.piv, r)[0]
                self.updates += 1
        return None

    def solve_first(self, z0: np.ndarray, q: np.ndarray, factors: tuple[LU | None, ...],
                    tolerance: float, max_iter: int) -> tuple[np.ndarray | None, LU | None]:
        """:meth:`solve` with each of ``factors`` in turn (None and repeats
        skipped) until one converges: (the root, the factors it took), else
        (None, None)."""
        tried: set[int] = set()
        for factor in factors:
            if factor is None or id(factor) in tried:
                continue
            tried.add(id(factor))
            z = self.solve(z0, q, factor, tolerance, max_iter)
            if z is not None:
                return z, factor
        return None, None

    def newton(self, z0: np.ndarray, q: np.ndarray, tolerance: float, max_iter: int) -> Root:
        """Newton's method from z0 to max |R| ≤ ``tolerance`` within
        ``max_iter`` iterations, keeping the factors while they converge fast
        (:data:`KEEP_FACTORS_BELOW`). A step from a fresh Jacobian that no
        halving (at most :data:`LINE_SEARCH_CUTS`) makes reduce max |R|
        ends the solve."""
        z = np.array(z0, float)
        r = self._residual(z, q)[0].ravel()
        size, factor, kept = float(np.max(np.abs(r))), None, False
        with np.errstate(over="ignore", invalid="ignore"):
            for it in range(max_iter):
                if size <= tolerance:
                    return Root(z, factor, it, True)
                if not np.isfinite(size):
                    return Root(z, factor, it, False)
                if not kept:
                    factor = self.factor(z, q)
                    if factor is None:
                        return Root(z, None, it, False)
                dz, lam = self.lu_solve(factor, r), 1.0
                for _ in range(LINE_SEARCH_CUTS + 1):
                    z_try = z - lam * dz
                    r_try = self._residual(z_try, q)[0].ravel()
                    size_try = float(np.max(np.abs(r_try)))
                    if size_try < size:
                        break
                    lam *= 0.5
                else:
                    if kept:                      # the kept factors failed: a fresh Jacobian
                        kept = False
                        continue
                    return Root(z, factor, it + 1, False)
                kept = lam == 1.0 and size_try < KEEP_FACTORS_BELOW * size
                z, r, size = z_try, r_try, size_try
        return Root(z, factor, max_iter, size <= tolerance)
