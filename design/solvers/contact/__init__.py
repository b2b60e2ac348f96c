"""Finger/object contact solvers, chosen by name.

``robust`` (default) is the continuation solver on the collocated beam;
``thesis-1`` and ``thesis-2`` are the thesis's Algorithms I and II, kept as
baselines.
"""

from design.solvers.contact.robust import RobustContact
from design.solvers.contact.thesis import AlgorithmI, AlgorithmII

CONTACT_METHODS = {"robust": RobustContact, "thesis-1": AlgorithmI, "thesis-2": AlgorithmII}
DEFAULT_CONTACT_METHOD = "robust"
#: per-method solver options: name -> (scene key, constructor argument, kind, lo, hi)
CONTACT_OPTIONS = {
    "robust": {"nodes": ("intervals", "int", 2, 200), "degree": ("degree", "int", 1, 9),
               "tolerance": ("tolerance", "float", 1e-15, 1e-4)},
    "thesis-1": {"step": ("step", "float", 1e-6, 10.0), "adaptive": ("adaptive", "bool", None, None),
                 "tolerance": ("tolerance", "float", 1e-9, 0.01),
                 "max_iterations": ("max_iter", "int", 1, 100000)},
    "thesis-2": {"nodes": ("nodes", "int", 5, 20001), "tolerance": ("tolerance", "float", 1e-15, 0.1),
                 "max_iterations": ("max_iter", "int", 1, 10000)},
}


def make_contact_solver(name: str, finger, friction: float, **options):
    return CONTACT_METHODS[name](finger, friction, **options)
