"""The settings a design problem's loop runs with: the problem's stated
solver options under the solve layer's policy, whoever built the problem
(its YAML file, or Python).

>>> from design.io.grasp_scene import GraspSettings
>>> s = loop_settings({"time_step": 0.01}, GraspSettings(contact_nodes=3))
>>> s.nlp.time_step, s.nlp.beam_intervals, s.simulator.max_step, s.simulator.max_newton_solves
(0.01, 3, 0.01, 300)
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import replace

from design.io.grasp_scene import GraspSettings
from design.solvers.optimize.transcription import NLPSettings
from design.solvers.optimize.trust_region import LOOP_SIMULATOR, LoopSettings

#: a design problem's ``solver`` keys (SI values), each optional
SOLVER_KEYS = ("method", "time_step", "beam_intervals", "max_iter", "tolerance",
               "outer_iterations", "trust_region", "cap_margin", "max_simulations", "lattice",
               "survey", "ipopt")
#: the design loops a problem may name: Ipopt's trust-region loop
#: (design/solvers/optimize/trust_region.py) or the pattern search on the
#: simulator (design/solvers/optimize/pattern_search.py)
LOOP_METHODS = ("trust-region", "pattern")


def loop_settings(solver: Mapping, scene: GraspSettings) -> LoopSettings:
    """The loop's settings from ``solver`` (a design problem's stated
    options, :data:`SOLVER_KEYS`; the rest take their defaults) and its
    grasp scene's ``settings``:

    * the loop's simulations use the scene's integrator, no looser than
      :data:`~design.solvers.optimize.trust_region.LOOP_SIMULATOR`'s
      tolerances (its accept/reject decisions compare holds a few ms apart)
      and with steps no longer than the NLP's time grid (whose view of a
      design must reproduce them; the verification runs at a quarter of it),
      each run with the loop's budget of contact work;
    * the NLP's finger mesh, and the loop simulations', is ``beam_intervals``
      if stated, else the scene's ``contact_nodes``.
    """
    n, d = NLPSettings(), LoopSettings()
    mesh = solver.get("beam_intervals", scene.contact_nodes)
    nlp = NLPSettings(solver.get("time_step", n.time_step), mesh, n.degree,
                      solver.get("max_iter", n.max_iter), solver.get("tolerance", n.tol),
                      dict(solver.get("ipopt", {})))
    given = scene.integrator
    simulator = replace(given, rtol=min(given.rtol, LOOP_SIMULATOR.rtol),
                        atol=min(given.atol, LOOP_SIMULATOR.atol),
                        max_step=min(given.max_step, nlp.time_step),
                        max_newton_solves=LOOP_SIMULATOR.max_newton_solves)
    return LoopSettings(nlp, solver.get("outer_iterations", d.outer_iterations),
                        solver.get("trust_region", d.radius), d.min_radius, simulator, mesh,
                        solver.get("cap_margin", d.cap_margin),
                        solver.get("method", d.method),
                        solver.get("max_simulations", d.max_simulations),
                        lattice=solver.get("lattice", d.lattice),
                        survey=solver.get("survey", d.survey))
