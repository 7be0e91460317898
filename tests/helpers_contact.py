"""Small contact problems written apart from the solver: two Kuhn-split blocks, one above the other, and a half
cylinder (one layer of prisms, for plane strain) standing on a flat block, the Hertz problem."""

from __future__ import annotations

import itertools

import numpy as np
from helpers_annulus import annulus_interfaces
from scipy.spatial import Delaunay

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


def half_cylinder_on_flat(radius_mm: float, thickness_mm: float, h_mm: float):
    """The half cylinder x^2 + y^2 <= R^2, y <= 0, z in [0, thickness], touching the top y = -R of a block below
    it (x in [-3, 3] mm, 1 mm deep) at x = 0; the cylinder's section is a polar grid with spacing h_mm over
    0.12 R of arc and of depth at the bottom, coarser away from it, Delaunay-triangulated and extruded one layer.
    The TetMesh (mm) and the block's node ids."""
    zone = 0.12 * radius_mm
    coarse = np.geomspace(zone / radius_mm, np.pi / 2, 12)[1:]
    fine = np.arange(-zone, zone + 1e-9, h_mm) / radius_mm
    theta = 1.5 * np.pi + np.concatenate([-coarse[::-1], fine, coarse])
    rim = radius_mm - np.arange(0.0, zone, h_mm)
    inner = (radius_mm - zone) * np.geomspace(1.0, 1e-2, 10)[1:]
    points = [np.zeros((1, 2))]
    for r in np.concatenate([rim, [radius_mm - zone], inner]):
        k = max(1, int((radius_mm - r) / (4 * h_mm)) + 1)  # thin the fine angles out with depth
        bottom = np.abs(theta - 1.5 * np.pi) <= zone / radius_mm + 1e-12
        th = np.unique(np.concatenate([theta[~bottom], theta[bottom][::k], [np.pi, 2 * np.pi]]))
        points.append(r * np.column_stack([np.cos(th), np.minimum(np.sin(th), 0.0)]))
    section = np.unique(np.round(np.vstack(points), 12), axis=0)
    n = len(section)
    tri = np.sort(Delaunay(section).simplices, axis=1)
    a, b, c = tri.T
    # each prism in three tetrahedra, every side quad split from its higher-numbered bottom corner: conforming
    prisms = np.concatenate([np.stack([a, b, c, a + n], 1), np.stack([b, c, a + n, b + n], 1),
                             np.stack([c, a + n, b + n, c + n], 1)])
    layer = [np.column_stack([section, np.full(n, z)]) for z in (0.0, thickness_mm)]
    fp, ft = box(np.linspace(-3.0, 3.0, 25), np.array([-radius_mm - 1.0, -radius_mm]), np.array([0.0, thickness_mm]))
    mesh = build_tetmesh(np.vstack([*layer, fp]), np.vstack([prisms, ft + 2 * n]),
                         annulus_interfaces(100.0, 200.0, 1.0), tol_mm=1e-9)
    assert len(mesh.points_mm) == 2 * n + len(fp)  # every node used: build_tetmesh kept the numbering
    return mesh, np.arange(2 * n, 2 * n + len(fp))
