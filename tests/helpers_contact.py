"""Small contact problems written apart from the solver: two Kuhn-split blocks, one above the other, and the
closed-form homogeneous uniaxial state of a compressible neo-Hookean block."""

from __future__ import annotations

import itertools

import numpy as np
from helpers_annulus import annulus_interfaces

from seadesign.mesh.tetmesh import build_tetmesh


def box(xs: np.ndarray, ys: np.ndarray, zs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Points (mm) and Kuhn-split tetrahedra of the grid xs x ys x zs."""
    X, Y, Z = np.meshgrid(xs, ys, zs, indexing="ij")
    pts = np.stack([X, Y, Z], axis=-1).reshape(-1, 3)
    ny, nz = len(ys), len(zs)

    def nid(i, j, k):
        return (i * ny + j) * nz + k

    i, j, k = (a.ravel() for a in np.meshgrid(np.arange(len(xs) - 1), np.arange(ny - 1), np.arange(nz - 1), indexing="ij"))
    tets = []
    for perm in itertools.permutations(range(3)):
        off, path = np.zeros(3, dtype=int), [nid(i, j, k)]
        for axis in perm:
            off[axis] += 1
            path.append(nid(i + off[0], j + off[1], k + off[2]))
        tets.append(np.stack(path, axis=1))
    return pts, np.concatenate(tets)


def two_blocks(base: tuple[int, int, int], top: tuple[int, int, int], side_mm: float = 1.0, height_mm: float = 1.0,
               gap_mm: float = 0.0):
    """A base block [0, side]^2 x [-height, 0] and a top block [0, side]^2 x [gap, gap + height], apart (no shared
    node), with (nx, ny, nz) cells each; the TetMesh (mm) and the node ids of the base and the top block."""
    p1, t1 = box(*(np.linspace(a, b, n + 1) for (a, b), n in zip(((0, side_mm), (0, side_mm), (-height_mm, 0)), base)))
    p2, t2 = box(*(np.linspace(a, b, n + 1) for (a, b), n in
                   zip(((0, side_mm), (0, side_mm), (gap_mm, gap_mm + height_mm)), top)))
    mesh = build_tetmesh(np.vstack([p1, p2]), np.vstack([t1, t2 + len(p1)]),
                         annulus_interfaces(100.0, 200.0, 1.0), tol_mm=1e-9)
    return mesh, np.arange(len(p1)), np.arange(len(p1), len(p1) + len(p2))
