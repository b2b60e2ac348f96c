"""Session settings for the test suite.

One BLAS thread. The toolkit's linear algebra is on small matrices (the
contact rootfinders' Jacobians, about 100 x 100, least squares in the
sliding velocity, Ipopt's KKT systems), where OpenBLAS's default of one
thread per core only adds hand-offs between threads, and on a shared
2-core machine with the other core busy each hand-off waits for the
scheduler: a 103 x 103 ``numpy.linalg.lstsq`` took 21 ms with two threads
against 1.5 ms with one, and test_reproduction_contact's FEM-peak test
8-38 s against 2.5 s. The variables must be set before numpy, scipy and
CasADi load their OpenBLAS copies, so here, before any test module is
imported; subprocesses (the ``design`` command in the CLI and interrupt
tests) inherit them. A value set by the caller is kept."""

import os
import sys
import warnings

for _variable in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS"):
    os.environ.setdefault(_variable, "1")

# numpy reads the variable when it loads its OpenBLAS: if a plugin imported it
# first, the setting above is ignored in this process (not in subprocesses)
if "numpy" in sys.modules:
    warnings.warn("numpy was imported before tests/conftest.py set one BLAS thread; "
                  "set OPENBLAS_NUM_THREADS=1 in the environment for the full speed")
