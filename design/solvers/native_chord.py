"""The chord iteration compiled with its residual: one C call per solve.

A chord iteration (design/solvers/newton.py's :class:`Chord`) is one
residual evaluation and one solve with kept LU factors. Called from Python,
each also costs a buffer call, LAPACK's getrs through its wrapper, numpy's
max |R| and an update. Here the loop is C, compiled into the residual's own
library (design/solvers/compiled.py), so a whole solve is one call: on the
football's contacts 17-21 µs a solve instead of 40 µs (106-107 unknowns),
40 µs instead of 70 µs (178).

The C loop does what :meth:`Chord.solve` does, in the same order: evaluate
R at z, stop when max |R| ≤ tolerance (None where it is not finite), else
z ← z - J⁻¹ R with the factors (LAPACK getrf's: column-major, row swaps in
turn); at most ``max_iter`` updates. Its triangular solves are plain loops,
four columns per pass (each element takes the same operations in the same
order as one column at a time). Its root agrees with the interpreted
loop's (getrs) to the tolerance, not to the bit (tests/test_newton.py).
"""

from __future__ import annotations

import ctypes

import numpy as np

from design.solvers.newton import LU

_SOURCE = r"""
#include <math.h>
#include <float.h>

/* r <- (LU)^-1 P r for getrf's factors of an N x N matrix (column-major,
   0-based swaps). Each triangle column by column, four columns per pass
   over r: every element takes the same operations in the same order as one
   column at a time, in a quarter of the passes. */
static void {name}_lu_solve(const casadi_real* lu, const int* piv, casadi_real* r) {{
  enum {{ N = {n} }};
  int j;
  for (int i = 0; i < N; ++i) {{
    int p = piv[i];
    if (p != i) {{ casadi_real t = r[i]; r[i] = r[p]; r[p] = t; }}
  }}
  for (j = 0; j + 4 <= N; j += 4) {{                   /* L y = r, L unit lower */
    const casadi_real *a = lu + j * N, *b = a + N, *c = b + N, *d = c + N;
    casadi_real v0 = r[j];
    r[j + 1] -= v0 * a[j + 1]; r[j + 2] -= v0 * a[j + 2]; r[j + 3] -= v0 * a[j + 3];
    casadi_real v1 = r[j + 1];
    r[j + 2] -= v1 * b[j + 2]; r[j + 3] -= v1 * b[j + 3];
    casadi_real v2 = r[j + 2];
    r[j + 3] -= v2 * c[j + 3];
    casadi_real v3 = r[j + 3];
    for (int i = j + 4; i < N; ++i) {{
      casadi_real x = r[i];
      x -= v0 * a[i]; x -= v1 * b[i]; x -= v2 * c[i]; x -= v3 * d[i];
      r[i] = x;
    }}
  }}
  for (; j < N; ++j) {{
    casadi_real v = r[j];
    for (int i = j + 1; i < N; ++i) r[i] -= v * lu[i + j * N];
  }}
  for (j = N - 1; j >= 3; j -= 4) {{                   /* U x = y */
    const casadi_real *a = lu + j * N, *b = a - N, *c = b - N, *d = c - N;
    r[j] /= a[j];
    casadi_real v0 = r[j];
    r[j - 1] -= v0 * a[j - 1]; r[j - 2] -= v0 * a[j - 2]; r[j - 3] -= v0 * a[j - 3];
    r[j - 1] /= b[j - 1];
    casadi_real v1 = r[j - 1];
    r[j - 2] -= v1 * b[j - 2]; r[j - 3] -= v1 * b[j - 3];
    r[j - 2] /= c[j - 2];
    casadi_real v2 = r[j - 2];
    r[j - 3] -= v2 * c[j - 3];
    r[j - 3] /= d[j - 3];
    casadi_real v3 = r[j - 3];
    for (int i = 0; i < j - 3; ++i) {{
      casadi_real x = r[i];
      x -= v0 * a[i]; x -= v1 * b[i]; x -= v2 * c[i]; x -= v3 * d[i];
      r[i] = x;
    }}
  }}
  for (; j >= 0; --j) {{
    r[j] /= lu[j + j * N];
    casadi_real v = r[j];
    for (int i = 0; i < j; ++i) r[i] -= v * lu[i + j * N];
  }}
}}

/* The chord method from z (overwritten by the last iterate), the updates
   made counted in *updates: 0 where max |R| <= tolerance was reached, -1
   where it diverged (R not finite) or did not converge within max_iter
   updates, -2 where the residual failed. */
CASADI_SYMBOL_EXPORT int {name}_chord(const casadi_real* q, const casadi_real* lu,
                                      const int* piv, casadi_real tolerance, int max_iter,
                                      casadi_real* z, int* updates) {{
  enum {{ N = {n} }};
  casadi_int sz_arg, sz_res, sz_iw, sz_w;
  {name}_work(&sz_arg, &sz_res, &sz_iw, &sz_w);
  const casadi_real* arg[sz_arg > 2 ? sz_arg : 2];
  casadi_real* res[sz_res > 1 ? sz_res : 1];
  casadi_int iw[sz_iw > 0 ? sz_iw : 1];
  casadi_real w[sz_w > 0 ? sz_w : 1];
  casadi_real r[N];
  arg[0] = z;
  arg[1] = q;
  res[0] = r;
  *updates = 0;
  for (int it = 0; it <= max_iter; ++it) {{
    if ({name}(arg, res, iw, w, 0)) return -2;
    casadi_real size = 0.0;
    for (int i = 0; i < N; ++i) {{
      casadi_real a = fabs(r[i]);
      if (!(a <= DBL_MAX)) return -1;
      if (a > size) size = a;
    }}
    if (size <= tolerance) return 0;
    if (it == max_iter) break;
    {name}_lu_solve(lu, piv, r);
    for (int i = 0; i < N; ++i) z[i] -= r[i];
    *updates = it + 1;
  }}
  return -1;
}}
"""


def source(name: str, n: int) -> str:
    """The C chord loop for the residual function ``name`` (z of size n, q)."""
    return _SOURCE.format(name=name, n=n)


class NativeChord:
    """The compiled chord loop of the residual ``name`` in ``library``."""

    def __init__(self, library: str, name: str, n_z: int, n_q: int):
        self._call = ctypes.CDLL(library)[f"{name}_chord"]
        self._call.restype = ctypes.c_int
        self._call.argtypes = [ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p,
                               ctypes.c_double, ctypes.c_int, ctypes.c_void_p, ctypes.c_void_p]
        # the call's z, q and update count, kept with their addresses
        self._z, self._q, self._updates = np.empty(n_z), np.empty(n_q), np.zeros(1, np.intc)
        self._at = self._z.ctypes.data, self._q.ctypes.data, self._updates.ctypes.data

    def solve(self, z0: np.ndarray, q: np.ndarray, factor: LU, tolerance: float,
              max_iter: int) -> tuple[np.ndarray | None, int]:
        """The root from z0 (max |R| ≤ ``tolerance`` within ``max_iter``
        updates) with ``factor``, or None; and the updates made. Not for
        concurrent calls."""
        self._z[:] = z0
        self._q[:] = q
        done = self._call(self._at[1], *factor.addresses, tolerance, max_iter, self._at[0],
                          self._at[2])
        if done == -2:
            raise RuntimeError(f"{self._call.__name__}: the residual failed")
        return (self._z.copy() if done == 0 else None), int(self._updates[0])
