"""Tetrahedral meshes of prismatic parts: a triangulated cross-section swept along z in layers.

The compliant element of the default studies is a straight extrusion (every feature runs through
the full thickness), and under torsion about z its field is nearly uniform in z. A swept mesh
puts the elements where k's error comes from (in-plane: bolt holes, beam-root fillets) without
paying for the same resolution through the thickness, which a free 3D mesh does.
"""

from __future__ import annotations

import math

import numpy as np


def layer_count(thickness_mm: float, size_mm: float, minimum: int = 4) -> int:
    """Layers of about `size_mm` (the in-plane target size) through `thickness_mm`, at least `minimum`."""
    return max(minimum, math.ceil(thickness_mm / size_mm - 1e-9))


def layer_fractions(layers: int) -> np.ndarray:
    """Layer boundaries as fractions of the thickness, graded toward both faces (Chebyshev
    spacing): the rigid couplings end at the faces, where the field varies most along z."""
    return 0.5 * (1.0 - np.cos(np.pi * np.arange(layers + 1) / layers))


def sweep_triangles(points_2d: np.ndarray, triangles: np.ndarray, z0_mm: float, thickness_mm: float,
                    layers: int) -> tuple[np.ndarray, np.ndarray]:
    """Points (n * (layers + 1), 3) and tetrahedra (3 * len(triangles) * layers, 4) of the prism
    mesh of a planar triangulation swept from z0 over thickness, each prism cut into three
    tetrahedra. The cut uses each triangle's vertices in ascending global order, so the
    diagonal of every shared quadrilateral face is the same on both sides (a conforming mesh)."""
    pts = np.asarray(points_2d, dtype=np.float64)[:, :2]
    tri = np.sort(np.asarray(triangles, dtype=np.int64), axis=1)
    n = len(pts)
    z = z0_mm + thickness_mm * layer_fractions(layers)
    points = np.column_stack([np.tile(pts, (layers + 1, 1)), np.repeat(z, n)])
    a, b, c = tri[:, 0], tri[:, 1], tri[:, 2]
    tets = []
    for k in range(layers):
        lo, hi = k * n, (k + 1) * n
        # prism (a, b, c | a', b', c') with a < b < c: [a b c c'], [a b b' c'], [a a' b' c']
        tets += [np.column_stack([a + lo, b + lo, c + lo, c + hi]),
                 np.column_stack([a + lo, b + lo, b + hi, c + hi]),
                 np.column_stack([a + lo, a + hi, b + hi, c + hi])]
    return points, np.concatenate(tets)
