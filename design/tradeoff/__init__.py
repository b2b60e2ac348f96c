"""Speed against accuracy: each solver level's settings, measured.

A *level* is what a scene kind exercises: ``beam`` (beam methods),
``contact`` (contact solvers), ``grasp`` (integrators) and ``design`` (the
optimiser's time grid). A study runs the level's settings on the scene,
measures each one's relative error against a finer reference and its wall
time (s), and marks the Pareto front of the trade and the cheapest setting
that meets a tolerance (:mod:`design.tradeoff.study`). ``design tradeoff``
(:mod:`design.tradeoff.run`, design/cli/tradeoff.py) prints and writes the result.
"""
