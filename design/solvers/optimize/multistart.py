"""Several starting designs for the design loop, and which of its answers coincide.

The hold time has many local optima (contact sequences change with the
design), so a single trust-region path finds one of them. A multistart
runs the loop from the baseline and from points of a scrambled Sobol
sequence in the scaled box [0, 1]^n, then groups the answers: two
verified designs are the same optimum when every scaled variable differs
by at most :data:`SAME_DESIGN` and their verified holds by at most
:data:`SAME_HOLD` (relative), joined transitively (single linkage).
"""

from __future__ import annotations

import numpy as np
from scipy.stats import qmc

#: scaled-variable distance (max norm) within which two optima are one
SAME_DESIGN = 0.05
#: relative hold difference within which two optima are one (the
#: verification's own tolerance, trust_region.HOLD_TOLERANCE)
SAME_HOLD = 0.02


def starting_designs(baseline: np.ndarray, starts: int, seed: int) -> list[np.ndarray]:
    """The baseline (scaled) and the first ``starts - 1`` points of a
    scrambled Sobol sequence in [0, 1]^n, the same for the same ``seed`` on
    every machine."""
    n, count = len(baseline), starts - 1
    if count < 1:
        return [np.asarray(baseline, float)]
    # the first points of a power-of-two run: a prefix of the same sequence
    power = int(np.ceil(np.log2(count)))
    others = qmc.Sobol(d=n, scramble=True, seed=seed).random_base2(power)[:count]
    return [np.asarray(baseline, float), *others]


def distinct_optima(designs: list[np.ndarray], holds: list[float]) -> list[list[int]]:
    """Groups of indices of the designs that are one optimum, each group in
    index order, the groups in order of their first index."""
    parent = list(range(len(designs)))

    def root(i: int) -> int:
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    for i in range(len(designs)):
        for j in range(i):
            near = np.max(np.abs(np.asarray(designs[i]) - designs[j])) <= SAME_DESIGN
            level = abs(holds[i] - holds[j]) <= SAME_HOLD * max(holds[i], holds[j], 1e-12)
            if near and level:
                parent[root(i)] = root(j)
    groups: dict[int, list[int]] = {}
    for i in range(len(designs)):
        groups.setdefault(root(i), []).append(i)
    return sorted(groups.values(), key=lambda g: g[0])
