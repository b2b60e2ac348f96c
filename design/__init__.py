"""Optimal design and timing of compliant graspers.

The package's API: :func:`simulate` solves a scene file (or its content),
:func:`check` validates a file, :func:`animate` writes a run's 3-D
animation from its output folder, :func:`design.api.solve` optimises a
design problem (``design.solve`` is the solvers' subpackage). The command
``design`` wraps them.
"""

import os as _os

__version__ = "0.1.0"

# Thousands of tiny dense solves (a few to ~100 unknowns): BLAS threads only
# contend for the cores. Measured on 2 busy cores, the Table 3-4 contact pass
# took 4.4 s with OpenBLAS's default threads and 2.6 s with one. A user's own
# setting wins; it has no effect if numpy was imported before this package.
_os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

__all__ = ["animate", "check", "simulate", "__version__"]


def __getattr__(name: str):
    """``design.animate``, ``design.check`` and ``design.simulate``, imported on first use: a
    process that needs only part of the toolkit (a study's worker, ``design
    --version``) does not load the solvers, reports and plotting (1.5 s)."""
    if name in ("animate", "check", "simulate"):
        from design import api
        return getattr(api, name)
    raise AttributeError(f"module 'design' has no attribute {name!r}")
