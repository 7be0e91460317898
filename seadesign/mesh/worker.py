"""Tetrahedralization in a child process, so a run that hangs or explodes can be killed.

Usage (internal): python -m seadesign.mesh.worker JOB_DIR. JOB_DIR holds job.json and the
input (surface.npz, or part.brep: a solid, or for a swept mesh the solid's bottom face); the
worker writes tets.npz (points in mm, tetrahedra).
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

from seadesign.mesh.extrude import sweep_triangles


def tetwild(vertices: np.ndarray, faces: np.ndarray, edge_length_fac: float, epsilon: float) -> tuple[np.ndarray, np.ndarray]:
    """fTetWild via pytetwild; both settings are relative to the bounding-box diagonal."""
    import pytetwild

    return pytetwild.tetrahedralize(
        vertices, faces.astype(np.int32), edge_length_fac=edge_length_fac, epsilon=epsilon, quiet=True
    )


MIN_SIZE_FRACTION = 0.05  # smallest element edge as a fraction of the target size
GMSH_ALGORITHMS = (1, 4, 10)  # 3D: Delaunay, then Frontal, then HXT for retries
GMSH_ALGORITHMS_2D = (6, 5, 1)  # 2D: Frontal-Delaunay, then Delaunay, then MeshAdapt


def _gmsh_model(brep: Path, size_mm: float, per_circle: float) -> None:
    """Start gmsh (single-threaded, so deterministic) on a BREP with the sizing options: size in
    mm, and with per_circle > 0 at least that many elements per full turn on curved geometry."""
    import gmsh

    gmsh.initialize(interruptible=False)
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.option.setNumber("General.NumThreads", 1)
    gmsh.model.occ.importShapes(str(brep))
    gmsh.model.occ.synchronize()
    gmsh.option.setNumber("Mesh.MeshSizeMax", size_mm)
    gmsh.option.setNumber("Mesh.MeshSizeMin", MIN_SIZE_FRACTION * size_mm)
    gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", per_circle)


def _gmsh_elements(dim: int, gmsh_type: int, nen: int) -> tuple[np.ndarray, np.ndarray]:
    """Node coordinates (n, 3) and elements (m, nen) as 0-based indices of the generated mesh."""
    import gmsh

    tags, coords, _ = gmsh.model.mesh.getNodes()
    types, _, nodes = gmsh.model.mesh.getElements(dim)
    if gmsh_type not in list(types):
        raise RuntimeError(f"gmsh produced no {'tetrahedra' if dim == 3 else 'triangles'}")
    elements = np.asarray(nodes[list(types).index(gmsh_type)], dtype=np.int64).reshape(-1, nen)
    index = np.full(int(tags.max()) + 1, -1, dtype=np.int64)
    index[tags.astype(np.int64)] = np.arange(len(tags))
    return np.asarray(coords, dtype=np.float64).reshape(-1, 3), index[elements]


def gmsh_brep(brep: Path, size_mm: float, per_circle: float = 0.0, attempt: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Tetrahedra of a CAD solid (points mm); retries switch the 3D algorithm, since repeating a
    deterministic failure cannot help."""
    import gmsh

    try:
        _gmsh_model(brep, size_mm, per_circle)
        gmsh.option.setNumber("Mesh.Algorithm3D", GMSH_ALGORITHMS[attempt % len(GMSH_ALGORITHMS)])
        gmsh.option.setNumber("Mesh.Optimize", 1)
        gmsh.model.mesh.generate(3)
        return _gmsh_elements(3, 4, 4)
    finally:
        gmsh.finalize()


def gmsh_face(brep: Path, size_mm: float, per_circle: float = 0.0, attempt: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Triangulation (points (n, 2) mm, triangles (m, 3)) of a planar face in a plane z = const;
    retries switch the 2D algorithm."""
    import gmsh

    try:
        _gmsh_model(brep, size_mm, per_circle)
        gmsh.option.setNumber("Mesh.Algorithm", GMSH_ALGORITHMS_2D[attempt % len(GMSH_ALGORITHMS_2D)])
        gmsh.model.mesh.generate(2)
        points, triangles = _gmsh_elements(2, 2, 3)
        return points[:, :2], triangles
    finally:
        gmsh.finalize()


def main(job_dir: str) -> None:
    job_dir = Path(job_dir)
    job = json.loads((job_dir / "job.json").read_text())
    if job["backend"] == "pytetwild":
        s = np.load(job_dir / "surface.npz")
        points, tets = tetwild(s["vertices"], s["faces"], job["edge_length_fac"], job["epsilon"])
    elif "swept" in job:
        points_2d, triangles = gmsh_face(job_dir / "part.brep", job["size_mm"], job["per_circle"], job["attempt"])
        sw = job["swept"]
        points, tets = sweep_triangles(points_2d, triangles, sw["z0_mm"], sw["thickness_mm"], sw["layers"])
    else:
        points, tets = gmsh_brep(job_dir / "part.brep", job["size_mm"], job["per_circle"], job["attempt"])
    np.savez(job_dir / "tets.npz", points=points, tets=tets)


if __name__ == "__main__":
    main(sys.argv[1])
