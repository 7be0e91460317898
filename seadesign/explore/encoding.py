"""Design axes as the unit cube the surrogates and the optimizer work in.

Each axis is one coordinate in [0, 1]: a continuous axis maps its bounds linearly; a numeric list
(or stepped range) maps its values linearly between its smallest and largest, and a point decodes to
the nearest listed value; a list of names (the material) maps its i-th name to i / (n - 1) (for two
names this is a one-hot column). Decoding snaps a point onto the values the axes allow, so the
surrogates are only ever asked about designs that exist.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from seadesign.design.space import Axis, Value

Point = tuple[tuple[str, Value], ...]  # (axis key, value) in axis order, as `Candidate.values`


def _levels(axis: Axis) -> np.ndarray:
    """The coordinates of a discrete axis's values."""
    n = len(axis.values)
    if n == 1:
        return np.zeros(1)
    if isinstance(axis.values[0], str):
        return np.arange(n) / (n - 1)
    v = np.asarray(axis.values, dtype=float)
    return (v - v.min()) / (v.max() - v.min())


@dataclass(frozen=True)
class Encoding:
    """The unit-cube coordinates of a study's design axes."""

    axes: tuple[Axis, ...]

    @property
    def dim(self) -> int:
        return len(self.axes)

    @property
    def keys(self) -> tuple[str, ...]:
        return tuple(a.key for a in self.axes)

    def grid_size(self) -> int | None:
        """How many designs the axes hold (None when an axis is continuous)."""
        if any(a.continuous for a in self.axes):
            return None
        return math.prod(len(a.values) for a in self.axes)

    def encode(self, point: Point) -> np.ndarray:
        """(dim,) coordinates of a design."""
        values = dict(point)
        out = np.empty(self.dim)
        for i, axis in enumerate(self.axes):
            v = values[axis.key]
            if axis.continuous:
                lo, hi = axis.bounds
                out[i] = (float(v) - lo) / (hi - lo)
            else:
                out[i] = _levels(axis)[axis.values.index(v)]
        return out

    def decode(self, x: np.ndarray) -> Point:
        """The design nearest to coordinates `x` (clipped to the cube; discrete axes snap to a value)."""
        x = np.clip(np.asarray(x, dtype=float), 0.0, 1.0)
        values = []
        for xi, axis in zip(x, self.axes):
            if axis.continuous:
                lo, hi = axis.bounds
                values.append((axis.key, float(lo + xi * (hi - lo))))
            else:
                values.append((axis.key, axis.values[int(np.argmin(np.abs(_levels(axis) - xi)))]))
        return tuple(values)

    def snap(self, X: np.ndarray) -> np.ndarray:
        """(n, dim) coordinates moved onto the designs the axes allow (vectorised `encode(decode(x))`)."""
        X = np.clip(np.atleast_2d(np.asarray(X, dtype=float)), 0.0, 1.0).copy()
        for i, axis in enumerate(self.axes):
            if not axis.continuous:
                levels = _levels(axis)
                X[:, i] = levels[np.argmin(np.abs(X[:, i, None] - levels[None, :]), axis=1)]
        return X

    def grid(self) -> np.ndarray:
        """Every design of an all-discrete space, (grid_size, dim)."""
        if self.grid_size() is None:
            raise ValueError("a continuous axis has no grid")
        mesh = np.meshgrid(*(_levels(a) for a in self.axes), indexing="ij")
        return np.column_stack([m.ravel() for m in mesh])
