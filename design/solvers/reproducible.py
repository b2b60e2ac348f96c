"""The same answer on every machine: the numerical settings a design run fixes,
and the libraries it records.

Round-off differences between runs come from three places: how many threads
the BLAS libraries split a product over (the order of a sum), which of its
kernels a CPU runs, and Ipopt's MUMPS ordering its matrix with METIS, which
draws random numbers. A design run uses one BLAS thread (numpy's OpenBLAS
through threadpoolctl, CasADi's own OpenBLAS through the environment it
reads when its linear-algebra plugins load; the toolkit's matrices are a
few hundred unknowns, where threads only add hand-offs) and an ordering
without random numbers (:data:`IPOPT_ORDERING`). What remains, the CPU's
kernels, is below the tolerances the design loop decides with
(design/solvers/optimize/trust_region.py), and result.json records the
libraries and settings (:func:`numerics`).
"""

from __future__ import annotations

import os
import tempfile
from contextlib import contextmanager
from functools import lru_cache

import casadi as ca
import numpy as np
import scipy
import threadpoolctl

#: MUMPS's fill-reducing ordering for Ipopt: approximate minimum fill (2),
#: deterministic, where the default may pick METIS (random numbers)
IPOPT_ORDERING = {"mumps_pivot_order": 2}
#: the environment variables of the BLAS libraries' threads and kernels
BLAS_VARIABLES = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_CORETYPE")


@contextmanager
def one_blas_thread():
    """Every BLAS the run uses on one thread: numpy's now, CasADi's when its
    plugins load (the variables stay set for the process's lifetime)."""
    os.environ["OPENBLAS_NUM_THREADS"] = "1"
    os.environ["OMP_NUM_THREADS"] = "1"
    with threadpoolctl.threadpool_limits(limits=1, user_api="blas"):
        yield


def ipopt_build() -> str:
    """Ipopt's version and linear solver as Ipopt prints them ("unknown" where
    it printed nothing)."""
    try:
        return _ipopt_line()
    except LookupError:
        return "unknown"


@lru_cache(maxsize=1)
def _ipopt_line() -> str:
    """The line Ipopt's banner names itself in (LookupError, not cached, where
    it printed none: a stand-in solver)."""
    x = ca.MX.sym("x")
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, "ipopt.out")
        solver = ca.nlpsol("version", "ipopt", {"x": x, "f": x ** 2},
                           {"print_time": False, "ipopt": {
                               "print_level": 0, "sb": "yes", "output_file": path,
                               "file_print_level": 5, "max_iter": 1}})
        solver(x0=1.0)
        lines = open(path, encoding="utf-8", errors="replace").readlines() \
            if os.path.exists(path) else []
    line = next((s for s in lines if s.startswith("This is Ipopt")), None)
    if line is None:
        raise LookupError("Ipopt printed no banner")
    return line.strip().removeprefix("This is ").rstrip(".")


def numerics() -> dict:
    """The numerical libraries and settings of this process, for result.json:
    ``numpy_blas`` lists every BLAS loaded, numpy's and scipy's (the
    simulations' contact solves factor their Jacobians with scipy's LAPACK)."""
    blas = [{"library": os.path.basename(i["filepath"]), "api": i.get("internal_api"),
             "version": i.get("version"), "kernels": i.get("architecture"),
             "threads": i.get("num_threads")} for i in threadpoolctl.threadpool_info()
            if i.get("user_api") == "blas"]
    return {"casadi": ca.__version__, "ipopt": ipopt_build(),
            "ipopt_ordering": IPOPT_ORDERING, "numpy": np.__version__,
            "scipy": scipy.__version__, "numpy_blas": blas,
            "environment": {v: os.environ.get(v) for v in BLAS_VARIABLES}}
