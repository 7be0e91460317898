"""Constrained two-objective test problems with known Pareto fronts, written apart from the explorer.

BNH (Binh & Korn 1997) and TNK (Tanaka 1995), as in Deb's "Multi-objective optimization using
evolutionary algorithms" (2001), table 9: the functions, the constraints, and each front in closed
form. IGD is computed here too, with objectives scaled by the reference front's range.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from seadesign.design.space import Axis
from seadesign.explore.encoding import Encoding


class Analytic:
    """An analytic problem in the explorer's protocol: every design is valid; evaluation is exact."""

    objectives = ("f1", "f2")
    margins = ("g1", "g2")
    outputs = ("f1", "f2")
    screened: tuple[str, ...] = ()

    def __init__(self, bounds: list[tuple[float, float]]) -> None:
        self.encoding = Encoding(tuple(Axis(f"x{i + 1}", bounds=b) for i, b in enumerate(bounds)))
        self.evaluations = 0

    def designs(self, X: np.ndarray) -> np.ndarray:
        lo = np.array([a.bounds[0] for a in self.encoding.axes])
        hi = np.array([a.bounds[1] for a in self.encoding.axes])
        return lo + np.asarray(X) * (hi - lo)

    def screen(self, X: np.ndarray) -> pd.DataFrame:
        return pd.DataFrame({"valid": np.ones(len(X), bool)})

    def evaluate(self, X: np.ndarray) -> pd.DataFrame:
        self.evaluations += len(X)
        x = self.designs(X)
        f1, f2, g1, g2 = self.functions(x[:, 0], x[:, 1])
        return pd.DataFrame({"solved": True, "f1": f1, "f2": f2, "g1": g1, "g2": g2})


class BNH(Analytic):
    """x1 in [0, 5], x2 in [0, 3]; min 4 x1^2 + 4 x2^2 and (x1 - 5)^2 + (x2 - 5)^2 subject to
    (x1 - 5)^2 + x2^2 <= 25 and (x1 - 8)^2 + (x2 + 3)^2 >= 7.7 (margins relative to the limits)."""

    def __init__(self) -> None:
        super().__init__([(0.0, 5.0), (0.0, 3.0)])

    @staticmethod
    def functions(x1, x2):
        return (4 * x1**2 + 4 * x2**2, (x1 - 5) ** 2 + (x2 - 5) ** 2,
                1 - ((x1 - 5) ** 2 + x2**2) / 25, ((x1 - 8) ** 2 + (x2 + 3) ** 2) / 7.7 - 1)

    @staticmethod
    def front(n: int = 2000) -> np.ndarray:
        """x1 = x2 in [0, 3], then x2 = 3 with x1 in [3, 5] (neither constraint is active on the front)."""
        t = np.linspace(0, 3, n // 2)
        s = np.linspace(3, 5, n // 2)
        return np.vstack([np.column_stack([8 * t**2, 2 * (t - 5) ** 2]),
                          np.column_stack([4 * s**2 + 36, (s - 5) ** 2 + 4])])


class TNK(Analytic):
    """x1, x2 in [0, pi]; min x1 and x2 subject to x1^2 + x2^2 - 1 - 0.1 cos(16 atan(x1 / x2)) >= 0 and
    (x1 - 0.5)^2 + (x2 - 0.5)^2 <= 0.5 (margins: the constraint functions themselves)."""

    def __init__(self) -> None:
        super().__init__([(0.0, np.pi), (0.0, np.pi)])

    @staticmethod
    def functions(x1, x2):
        return (x1, x2, x1**2 + x2**2 - 1 - 0.1 * np.cos(16 * np.arctan2(x1, x2)),
                0.5 - ((x1 - 0.5) ** 2 + (x2 - 0.5) ** 2))

    @staticmethod
    def front(n: int = 20000) -> np.ndarray:
        """The non-dominated part of the boundary of the first constraint (in polar form, the angle
        measured from the x2 axis: r^2 = 1 + 0.1 cos(16 theta)) inside the second constraint."""
        theta = np.linspace(0, np.pi / 2, n)
        r = np.sqrt(1 + 0.1 * np.cos(16 * theta))
        F = np.column_stack([r * np.sin(theta), r * np.cos(theta)])
        F = F[(F[:, 0] - 0.5) ** 2 + (F[:, 1] - 0.5) ** 2 <= 0.5]
        order = np.argsort(F[:, 0])
        F = F[order]
        keep = F[:, 1] < np.minimum.accumulate(np.concatenate([[np.inf], F[:-1, 1]]))
        return F[keep]


def igd(obtained: np.ndarray, reference: np.ndarray) -> float:
    """Mean distance from each reference point to the nearest obtained point, both scaled by the reference
    front's range per objective (inf when nothing was obtained)."""
    if len(obtained) == 0:
        return float("inf")
    lo, span = reference.min(axis=0), np.ptp(reference, axis=0)
    R, A = (reference - lo) / span, (np.asarray(obtained) - lo) / span
    return float(np.mean(np.min(np.linalg.norm(R[:, None, :] - A[None, :, :], axis=2), axis=1)))


class StripedBNH(BNH):
    """BNH whose designs with x1 in stripes (the first 30 % of every twentieth of its range) cannot be built:
    screening finds them invalid. The stripes are finer than a classifier learns from a few dozen designs,
    so proposals keep screening invalid."""

    STRIPES, INVALID_FRACTION = 20, 0.3

    def screen(self, X: np.ndarray) -> pd.DataFrame:
        return pd.DataFrame({"valid": np.mod(self.STRIPES * np.asarray(X)[:, 0], 1.0) >= self.INVALID_FRACTION})
