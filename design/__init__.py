"""Optimal design and timing of compliant graspers.

The package's API: :func:`simulate` solves a scene file (or its content),
:func:`check` validates one. The command ``design`` wraps both.
"""

__version__ = "0.1.0"

from design.api import check, simulate  # noqa: E402

__all__ = ["check", "simulate", "__version__"]
