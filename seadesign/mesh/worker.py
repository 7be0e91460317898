"""Tetrahedralization in a child process, so a run that hangs or explodes can be killed.

Usage (internal): python -m seadesign.mesh.worker JOB_DIR. JOB_DIR holds job.json and the
input (surface.npz or part.brep); the worker writes tets.npz (points in mm, tetrahedra).
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np


def tetwild(vertices: np.ndarray, faces: np.ndarray, edge_length_fac: float, epsilon: float) -> tuple[np.ndarray, np.ndarray]:
    """fTetWild via pytetwild; both settings are relative to the bounding-box diagonal."""
    import pytetwild

    return pytetwild.tetrahedralize(
        vertices, faces.astype(np.int32), edge_length_fac=edge_length_fac, epsilon=epsilon, quiet=True
    )


GMSH_ALGORITHMS = (1, 4, 10)  # Delaunay, then Frontal, then HXT for retries


def gmsh_brep(brep: Path, size_mm: float, attempt: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """gmsh on the exact CAD geometry, single-threaded (deterministic); size in mm. Retries
    switch the 3D algorithm, since repeating a deterministic failure cannot help."""
    import gmsh

    gmsh.initialize(interruptible=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.option.setNumber("General.NumThreads", 1)
        gmsh.model.occ.importShapes(str(brep))
        gmsh.model.occ.synchronize()
        gmsh.option.setNumber("Mesh.MeshSizeMax", size_mm)
        gmsh.option.setNumber("Mesh.MeshSizeMin", 0.1 * size_mm)
        gmsh.option.setNumber("Mesh.Algorithm3D", GMSH_ALGORITHMS[attempt % len(GMSH_ALGORITHMS)])
        gmsh.option.setNumber("Mesh.Optimize", 1)
        gmsh.model.mesh.generate(3)
        tags, coords, _ = gmsh.model.mesh.getNodes()
        types, _, nodes = gmsh.model.mesh.getElements(3)
        if 4 not in list(types):
            raise RuntimeError("gmsh produced no tetrahedra")
        tet_nodes = np.asarray(nodes[list(types).index(4)], dtype=np.int64).reshape(-1, 4)
    finally:
        gmsh.finalize()
    index = np.full(int(tags.max()) + 1, -1, dtype=np.int64)
    index[tags.astype(np.int64)] = np.arange(len(tags))
    return np.asarray(coords, dtype=np.float64).reshape(-1, 3), index[tet_nodes]


def main(job_dir: str) -> None:
    job_dir = Path(job_dir)
    job = json.loads((job_dir / "job.json").read_text())
    if job["backend"] == "pytetwild":
        s = np.load(job_dir / "surface.npz")
        points, tets = tetwild(s["vertices"], s["faces"], job["edge_length_fac"], job["epsilon"])
    else:
        points, tets = gmsh_brep(job_dir / "part.brep", job["size_mm"], job["attempt"])
    np.savez(job_dir / "tets.npz", points=points, tets=tets)


if __name__ == "__main__":
    main(sys.argv[1])
