"""result.json's record of the numerical libraries a run computes with."""

import os

import casadi as ca
import numpy as np
import scipy

from design.solvers.reproducible import numerics


def test_numerics_names_the_libraries_and_the_blas_threads():
    """The versions are those of the modules this process imported; every
    BLAS loaded (numpy's and scipy's, whose LAPACK factors the contact
    Jacobians) is listed with its threads, one each as the package sets
    them unless the environment said otherwise."""
    n = numerics()
    assert (n["casadi"], n["numpy"], n["scipy"]) == (ca.__version__, np.__version__,
                                                     scipy.__version__)
    assert n["ipopt"].startswith("Ipopt version")
    assert n["numpy_blas"] and all(b["library"] for b in n["numpy_blas"])
    threads = int(os.environ.get("OPENBLAS_NUM_THREADS", "1"))
    assert all(b["threads"] == threads for b in n["numpy_blas"] if b["api"] == "openblas")
    assert n["environment"]["OPENBLAS_NUM_THREADS"] == os.environ.get("OPENBLAS_NUM_THREADS")
