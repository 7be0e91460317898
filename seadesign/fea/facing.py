"""Surfaces of a part that face each other across open space, and the gap between them as it deforms.

Two boundary vertices face each other when their outward normals are opposed (cosine below -0.5), they
lie within the search distance (a k-d tree of the deformed positions, rebuilt at each state) and they
faced each other across open space at rest (a positive gap then: not the two sides of a thin wall). The
gap is their separation along the normals, negative once they overlap. Positions in m, gaps reported in mm.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from seadesign.fea.torsion import MM


@dataclass(frozen=True)
class FacingSurfaces:
    """The boundary of a mesh for the gap search: its vertices, linear facets and outward normals at rest."""

    nodes_m: np.ndarray  # (N, 3) all nodes at rest
    vertices: np.ndarray  # boundary vertices (node ids)
    faces: np.ndarray  # (k, 3) boundary facets (node ids)
    rest_normals: np.ndarray  # (len(vertices), 3) outward unit normals at rest
    search_m: float  # vertices further apart are never paired

    @classmethod
    def of(cls, nodes_m: np.ndarray, faces: np.ndarray, search_mm: float) -> "FacingSurfaces":
        vertices = np.unique(faces)
        return cls(nodes_m, vertices, faces, vertex_normals(nodes_m, faces, vertices), search_mm * MM)

    def min_gap_mm(self, u: np.ndarray) -> tuple[float, tuple[float, float, float]]:
        """Smallest gap (mm) between facing vertices of the part deformed by u (m), and where (the pair's
        midpoint at rest, mm); inf and NaN without a facing pair within the search distance."""
        x0 = self.nodes_m[self.vertices]
        x = x0 + u[self.vertices]
        n = vertex_normals(self.nodes_m + u, self.faces, self.vertices)
        pairs = self._pairs(x, n, self.search_m, -0.5)
        if not len(pairs):
            return float("inf"), (float("nan"),) * 3
        gaps = _gap(x, n, pairs)
        k = int(np.argmin(gaps))
        return float(gaps[k] / MM), tuple(float(c) for c in x0[pairs[k]].mean(axis=0) / MM)

    def facing_vertices(self, u: np.ndarray, distance_m: float, cosine: float) -> np.ndarray:
        """The vertices (node ids) within `distance_m` of a vertex they face at u (normals' cosine below `cosine`,
        a positive gap at rest)."""
        x = self.nodes_m[self.vertices] + u[self.vertices]
        return self.vertices[np.unique(self._pairs(x, vertex_normals(self.nodes_m + u, self.faces, self.vertices),
                                                   distance_m, cosine))]

    def _pairs(self, x: np.ndarray, n: np.ndarray, distance_m: float, cosine: float) -> np.ndarray:
        """Vertex pairs (rows of `vertices`) within `distance_m` at positions x, normals n, that face each other."""
        pairs = cKDTree(x).query_pairs(distance_m, output_type="ndarray")
        if len(pairs):
            pairs = pairs[np.einsum("ij,ij->i", n[pairs[:, 0]], n[pairs[:, 1]]) < cosine]
        if len(pairs):
            pairs = pairs[_gap(self.nodes_m[self.vertices], self.rest_normals, pairs) > 0]
        return pairs


def vertex_normals(x: np.ndarray, faces: np.ndarray, vertices: np.ndarray) -> np.ndarray:
    """Unit outward normals (area-weighted) of the boundary vertices at positions x."""
    tri = x[faces]
    normal = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    vn = np.zeros_like(x)
    for k in range(3):
        np.add.at(vn, faces[:, k], normal)
    return vn[vertices] / np.linalg.norm(vn[vertices], axis=1)[:, None]


def _gap(x: np.ndarray, n: np.ndarray, pairs: np.ndarray) -> np.ndarray:
    """Separation of vertex pairs along their normals (m); positive across open space, negative through material."""
    d = x[pairs[:, 1]] - x[pairs[:, 0]]
    return 0.5 * np.einsum("ij,ij->i", d, n[pairs[:, 0]] - n[pairs[:, 1]])
