"""Closed triangle surfaces (mm) from a CadQuery solid or an STL file, in part coordinates."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from seadesign.errors import MeshError

# proper rotations taking the named axis to +z
AXES = {
    "x": np.array([[0, 0, -1], [0, 1, 0], [1, 0, 0]]),
    "y": np.array([[1, 0, 0], [0, 0, -1], [0, 1, 0]]),
    "z": np.eye(3),
}


def merge_vertices(vertices: np.ndarray, faces: np.ndarray, tol_mm: float = 1e-6) -> tuple[np.ndarray, np.ndarray]:
    """Weld vertices closer than tol_mm (per-face tessellation duplicates) and drop collapsed faces."""
    pairs = cKDTree(vertices).query_pairs(tol_mm, output_type="ndarray")
    n = len(vertices)
    graph = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(n, n)) if len(pairs) else coo_matrix((n, n))
    _, label = connected_components(graph, directed=False)
    _, first = np.unique(label, return_index=True)
    merged = vertices[first]
    f = label[faces]
    keep = (f[:, 0] != f[:, 1]) & (f[:, 1] != f[:, 2]) & (f[:, 2] != f[:, 0])
    return merged, f[keep]


def check_closed(faces: np.ndarray, what: str) -> None:
    """Raise MeshError unless every edge is shared by exactly two faces (a closed 2-manifold)."""
    e = np.sort(faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
    _, counts = np.unique(e, axis=0, return_counts=True)
    if np.any(counts != 2):
        raise MeshError(
            f"{what}: the surface is not closed ({int(np.sum(counts == 1))} open and "
            f"{int(np.sum(counts > 2))} non-manifold edges); repair it or rebuild the solid"
        )


def tessellate_solid(solid, tolerance_mm: float, angular_tolerance_rad: float = 0.2) -> tuple[np.ndarray, np.ndarray]:
    """Closed, welded triangulation (mm) of a CadQuery solid."""
    try:
        verts, tris = solid.tessellate(tolerance_mm, angular_tolerance_rad)
    except Exception as exc:  # OCC raises assorted types
        raise MeshError(f"tessellating the solid failed ({exc}); check that the geometry is a valid solid") from None
    v = np.array([(p.x, p.y, p.z) for p in verts], dtype=np.float64)
    f = np.array(tris, dtype=np.int64)
    if len(f) == 0:
        raise MeshError("tessellating the solid gave no triangles; is the solid empty?")
    v, f = merge_vertices(v, f, 1e-6 * max(1.0, float(np.ptp(v, axis=0).max())))
    check_closed(f, "tessellated solid")
    return v, f


def load_stl(path: str | Path, axis: str = "y") -> tuple[np.ndarray, np.ndarray]:
    """An STL in mm rotated so its `axis` ("x", "y" or "z") becomes +z, shifted to z in [0, t];
    the axis is kept through the origin (x, y unchanged apart from the rotation)."""
    import trimesh

    path = Path(path)
    if axis not in AXES:
        raise MeshError(f"--axis must be one of x, y, z (got {axis!r})")
    if not path.is_file():
        raise MeshError(f"STL file {path} does not exist")
    try:
        m = trimesh.load(path, force="mesh", process=False)
    except Exception as exc:
        raise MeshError(f"cannot read {path} as STL ({exc})") from None
    v = np.asarray(m.vertices, dtype=np.float64) @ AXES[axis].T
    f = np.asarray(m.faces, dtype=np.int64)
    v, f = merge_vertices(v, f, 1e-6 * max(1.0, float(np.ptp(v, axis=0).max())))
    check_closed(f, str(path))
    v[:, 2] -= v[:, 2].min()
    return v, f
