"""Richardson extrapolation of a mesh-convergence series."""

from __future__ import annotations

import numpy as np
from scipy.optimize import brentq


def richardson(sizes: list[float], values: list[float]) -> dict[str, float]:
    """Extrapolate values(h) = v0 + C h^p from the three finest of (size, value) pairs (any size
    ratios). Returns v0, the observed order p and each size's relative error |v - v0| / |v0|
    (keys "rel_error_h=<size>"). When the series is not monotone or not yet in the asymptotic
    range (differences growing as h shrinks), no order exists and v0 and the errors are nan.
    """
    order = np.argsort(sizes)[::-1]
    h = np.asarray(sizes, dtype=float)[order][-3:]
    v = np.asarray(values, dtype=float)[order][-3:]
    if len(h) < 3:
        raise ValueError("Richardson extrapolation needs at least three mesh sizes")
    d1, d2 = v[0] - v[1], v[1] - v[2]
    p = v0 = float("nan")
    if d1 * d2 > 0:
        ratio = d1 / d2

        def f(q: float) -> float:
            return (h[0] ** q - h[1] ** q) / (h[1] ** q - h[2] ** q) - ratio

        try:
            p = float(brentq(f, 0.05, 12.0))
            v0 = float(v[2] - d2 / ((h[1] / h[2]) ** p - 1.0))
        except ValueError:
            pass
    out = {"extrapolated": v0, "order": p}
    for hs, vs in zip(sizes, values):
        out[f"rel_error_h={hs:g}"] = abs(vs - v0) / abs(v0)
    return out
