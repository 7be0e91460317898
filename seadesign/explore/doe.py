"""The initial design of experiments: the full factorial of a small all-discrete space, a Latin
hypercube otherwise.

The Latin hypercube (scipy.stats.qmc, optimised for centred discrepancy, seeded) is snapped onto the
designs the axes allow and repeated designs are dropped; `pool` gives further space-filling points
to replace designs that screening finds invalid.
"""

from __future__ import annotations

import numpy as np
from scipy.stats import qmc

from seadesign.explore.encoding import Encoding


def initial_size(dim: int, budget: int) -> int:
    """Designs in the initial sample: 3 per axis (at least 4), and at most half the budget, so that
    the search has the other half."""
    return max(2, min(max(4, 3 * dim), budget // 2))


def initial_design(encoding: Encoding, n: int, seed: int) -> np.ndarray:
    """(m, dim) unit-cube designs: every design when the space is discrete with at most `n` of them,
    else `n` Latin-hypercube points snapped to the allowed values (m <= n after dropping repeats)."""
    size = encoding.grid_size()
    if size is not None and size <= n:
        return encoding.grid()
    return pool(encoding, n, seed)


def pool(encoding: Encoding, n: int, seed: int) -> np.ndarray:
    """`n` seeded Latin-hypercube points snapped to the allowed values, repeats dropped (order kept)."""
    lhs = qmc.LatinHypercube(d=encoding.dim, optimization="random-cd", rng=np.random.default_rng(seed))
    return unique_rows(encoding.snap(lhs.random(n)))


def unique_rows(X: np.ndarray, decimals: int = 12) -> np.ndarray:
    """The rows of X without repeats, in first-seen order."""
    _, first = np.unique(np.round(X, decimals), axis=0, return_index=True)
    return X[np.sort(first)]
