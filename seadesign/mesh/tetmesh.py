"""The tetrahedral mesh handed to FEA: points, tetrahedra, named boundary facets, quality.

Coordinates are millimetres in part coordinates (axis +z, part spans z in [0, thickness]).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from seadesign.errors import MeshError
from seadesign.design.interfaces import Interfaces


@dataclass(frozen=True)
class MeshQuality:
    """Element count and shape measures (min dihedral angle in degrees; aspect ratio is
    circumradius / (3 x inradius), 1 for a regular tetrahedron)."""

    n_nodes: int
    n_tets: int
    min_dihedral_deg: float
    max_aspect_ratio: float
    mean_aspect_ratio: float

    def as_dict(self) -> dict:
        """Plain-number form for JSON and tables."""
        return {
            "mesh_nodes": self.n_nodes,
            "mesh_tets": self.n_tets,
            "mesh_min_dihedral_deg": self.min_dihedral_deg,
            "mesh_max_aspect_ratio": self.max_aspect_ratio,
            "mesh_mean_aspect_ratio": self.mean_aspect_ratio,
        }


@dataclass(frozen=True)
class TetMesh:
    """Linear tetrahedra (positively oriented) with named boundary facets.

    points_mm: (n, 3) node coordinates in mm. tets: (m, 4) node indices.
    boundary_faces: (k, 3) node indices of the facets that belong to exactly one tetrahedron.
    boundaries: name -> indices into boundary_faces ("bore", "hub_hole_<i>", "ring_hole_<i>",
    "outer"); only names with at least one facet are present.
    info: how the mesh was made (backend, settings, cache key, seconds).
    """

    points_mm: np.ndarray
    tets: np.ndarray
    boundary_faces: np.ndarray
    boundaries: dict[str, np.ndarray]
    quality: MeshQuality
    info: dict = field(default_factory=dict)

    def boundary_nodes(self, names: list[str] | tuple[str, ...]) -> np.ndarray:
        """Sorted unique vertex indices of the facets of the named boundaries."""
        missing = [n for n in names if n not in self.boundaries]
        if missing:
            raise MeshError(
                f"boundary {missing} not found in the mesh (present: {sorted(self.boundaries)}); "
                "check the Interfaces radii against the geometry"
            )
        faces = np.concatenate([self.boundary_faces[self.boundaries[n]] for n in names])
        return np.unique(faces)


def orient_positive(points: np.ndarray, tets: np.ndarray) -> np.ndarray:
    """Tetrahedra reordered so every signed volume is positive; degenerate ones raise MeshError."""
    p = points[tets]
    vol6 = np.einsum("ij,ij->i", np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), p[:, 3] - p[:, 0])
    scale = np.ptp(points, axis=0).max() ** 3
    if np.any(np.abs(vol6) <= 1e-14 * scale):
        raise MeshError(f"{int(np.sum(np.abs(vol6) <= 1e-14 * scale))} degenerate (zero-volume) tetrahedra")
    out = tets.copy()
    neg = vol6 < 0
    out[neg, 1], out[neg, 2] = tets[neg, 2], tets[neg, 1]
    return out


def boundary_facets(tets: np.ndarray) -> np.ndarray:
    """(k, 3) facets that belong to exactly one tetrahedron, oriented outward."""
    local = np.array([[1, 2, 3], [0, 3, 2], [0, 1, 3], [0, 2, 1]])  # outward for positive tets
    faces = tets[:, local].reshape(-1, 3)
    key = np.sort(faces, axis=1)
    _, first, counts = np.unique(key, axis=0, return_index=True, return_counts=True)
    return faces[first[counts == 1]]


def quality(points: np.ndarray, tets: np.ndarray) -> MeshQuality:
    """Mesh quality: min dihedral angle (deg) and radius-ratio aspect measure."""
    p = points[tets]
    pairs = [(0, 1, 2, 3), (0, 2, 1, 3), (0, 3, 1, 2), (1, 2, 0, 3), (1, 3, 0, 2), (2, 3, 0, 1)]
    min_dih = np.full(len(tets), np.pi)
    for i, j, k, l in pairs:
        e = p[:, j] - p[:, i]
        n1 = np.cross(e, p[:, k] - p[:, i])
        n2 = np.cross(e, p[:, l] - p[:, i])
        c = np.einsum("ij,ij->i", n1, n2) / (np.linalg.norm(n1, axis=1) * np.linalg.norm(n2, axis=1))
        min_dih = np.minimum(min_dih, np.arccos(np.clip(c, -1.0, 1.0)))
    a, b, c = p[:, 1] - p[:, 0], p[:, 2] - p[:, 0], p[:, 3] - p[:, 0]
    vol = np.abs(np.einsum("ij,ij->i", np.cross(a, b), c)) / 6.0
    area = sum(
        0.5 * np.linalg.norm(np.cross(p[:, f[1]] - p[:, f[0]], p[:, f[2]] - p[:, f[0]]), axis=1)
        for f in ((0, 1, 2), (0, 1, 3), (0, 2, 3), (1, 2, 3))
    )
    inradius = 3.0 * vol / area
    # circumradius: |a^2 (b x c) + b^2 (c x a) + c^2 (a x b)| / (12 V)
    num = (
        (a * a).sum(1)[:, None] * np.cross(b, c)
        + (b * b).sum(1)[:, None] * np.cross(c, a)
        + (c * c).sum(1)[:, None] * np.cross(a, b)
    )
    circumradius = np.linalg.norm(num, axis=1) / (12.0 * vol)
    ratio = circumradius / (3.0 * inradius)
    return MeshQuality(
        n_nodes=int(len(points)),
        n_tets=int(len(tets)),
        min_dihedral_deg=float(np.degrees(min_dih.min())),
        max_aspect_ratio=float(ratio.max()),
        mean_aspect_ratio=float(ratio.mean()),
    )


def tag_boundaries(
    points: np.ndarray, faces: np.ndarray, interfaces: Interfaces, tol_mm: float
) -> dict[str, np.ndarray]:
    """Name the boundary facets that lie on the interface cylinders (hole walls, bore, outer face).

    A facet belongs to a cylinder of radius R about axis point c when all three vertices are
    within tol_mm of it and its normal is radial (|n_z| < 0.3). Only boundary facets are passed
    in, so interior facets can never be tagged.
    """
    tri = points[faces]
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    nz = np.abs(n[:, 2]) / np.linalg.norm(n, axis=1)
    radial = nz < 0.3

    def on_cylinder(cx: float, cy: float, radius: float) -> np.ndarray:
        d = np.hypot(tri[:, :, 0] - cx, tri[:, :, 1] - cy)
        return radial & np.all(np.abs(d - radius) <= tol_mm, axis=1)

    cylinders: dict[str, tuple[float, float, float]] = {}
    if interfaces.bore_radius_mm > 0:
        cylinders["bore"] = (0.0, 0.0, interfaces.bore_radius_mm)
    for i, h in enumerate(interfaces.hub_holes):
        cylinders[f"hub_hole_{i}"] = (h.x_mm, h.y_mm, h.radius_mm)
    for i, h in enumerate(interfaces.ring_holes):
        cylinders[f"ring_hole_{i}"] = (h.x_mm, h.y_mm, h.radius_mm)
    cylinders["outer"] = (0.0, 0.0, interfaces.ring_outer_radius_mm)

    tags: dict[str, np.ndarray] = {}
    for name, (cx, cy, r) in cylinders.items():
        idx = np.flatnonzero(on_cylinder(cx, cy, r))
        if len(idx):
            tags[name] = idx
    return tags


def build_tetmesh(
    points_mm: np.ndarray, tets: np.ndarray, interfaces: Interfaces, tol_mm: float, info: dict | None = None
) -> TetMesh:
    """TetMesh from raw arrays: drop unused nodes, orient, extract and name boundary facets."""
    points_mm = np.asarray(points_mm, dtype=np.float64)
    tets = np.asarray(tets, dtype=np.int64)
    if tets.ndim != 2 or tets.shape[1] != 4 or len(tets) == 0:
        raise MeshError(f"expected (m, 4) tetrahedra, got shape {tets.shape}")
    used, tets = np.unique(tets, return_inverse=True)
    tets = tets.reshape(-1, 4)
    points_mm = points_mm[used]
    tets = orient_positive(points_mm, tets)
    faces = boundary_facets(tets)
    return TetMesh(
        points_mm=points_mm,
        tets=tets,
        boundary_faces=faces,
        boundaries=tag_boundaries(points_mm, faces, interfaces, tol_mm),
        quality=quality(points_mm, tets),
        info=dict(info or {}),
    )
