"""Calibrating models from measurements (``design fit``).

* :mod:`design.calibration.kernel`: the compliance c(s) = 1/EI(s) as a piecewise-linear
  profile on knots, and the small-deflection kernel that makes every measured
  deflection and slope linear in it.
* :mod:`design.calibration.convex`: the convex fit of c >= 0 (cvxpy, Clarabel) with a
  smoothness penalty whose weight generalised cross-validation (or the
  L-curve) picks, and its confidence band.
* :mod:`design.calibration.elastica`: predictions of the planar elastica at measured
  points, the uniform EI that fits them best, and the nonlinear
  least-squares problem on the collocated elastica (CasADi + Ipopt).
* :mod:`design.calibration.refinement`: the large-deflection fit of ln(1/EI) along a
  path of weights, and its band.
* :mod:`design.calibration.exponential`: the thesis's exponential family
  EI = E (A e^(a s) + B e^(b s) + C) projected onto a fitted profile.
* :mod:`design.calibration.belt`: belt speed profiles from an encoder log.

Conventions as in :mod:`design.physics.beam`: s is arc length from the clamp
(m), a load of magnitude F (N) at arc length ``at`` pushes along
F (-cos α, sin α) in the finger frame; everything is SI.
"""
