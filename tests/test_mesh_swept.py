"""Swept meshes of prismatic parts: conformity, volume, detection, and agreement with a free 3D mesh."""

from __future__ import annotations

import cadquery as cq
import numpy as np
import pytest
from helpers_parts import holed_annulus
from scipy.spatial import Delaunay

from seadesign.fea.torsion import solve_unit_torsion
from seadesign.mesh import mesh_part, prismatic_section
from seadesign.mesh.extrude import layer_fractions, sweep_triangles
from seadesign.mesh.tetmesh import boundary_facets, orient_positive


def test_swept_mesh_is_conforming_and_fills_the_prism():
    rng = np.random.default_rng(0)
    pts = np.vstack([[[0, 0], [3, 0], [3, 2], [0, 2]], rng.uniform([0.1, 0.1], [2.9, 1.9], size=(40, 2))])
    tri = Delaunay(pts).simplices
    layers, thickness = 4, 1.5
    points, tets = sweep_triangles(pts, tri, 0.0, thickness, layers)
    tets = orient_positive(points, tets)  # raises on a degenerate tetrahedron
    p = points[tets]
    volume = np.abs(np.einsum("ij,ij->i", np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), p[:, 3] - p[:, 0])).sum() / 6
    assert volume == pytest.approx(3 * 2 * thickness, rel=1e-12)
    # conforming: the only unshared facets are the caps and the side walls, two per boundary edge per layer
    edges = np.sort(np.vstack([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [0, 2]]]), axis=1)
    _, counts = np.unique(edges, axis=0, return_counts=True)
    assert len(boundary_facets(tets)) == 2 * len(tri) + 2 * layers * int(np.sum(counts == 1))


def test_layers_are_graded_toward_both_faces():
    f = layer_fractions(5)
    assert f[0] == 0 and f[-1] == pytest.approx(1)
    steps = np.diff(f)
    assert np.allclose(steps, steps[::-1]) and steps[0] < steps[2]


def test_prismatic_parts_are_detected_and_others_meshed_in_3d(tmp_path):
    solid, ifc = holed_annulus()
    face, z0, height = prismatic_section(solid)
    assert (z0, height) == pytest.approx((0.0, 5.0)) and face.Area() * 5.0 == pytest.approx(solid.Volume())
    counterbored = (cq.Workplane("XY").circle(20.0).circle(3.0).extrude(5.0)
                    .faces(">Z").workplane().hole(10.0, 2.0)).val()
    assert prismatic_section(counterbored) is None
    mesh = mesh_part(counterbored, ifc, 1.0, 4.0, cache_dir=tmp_path)
    assert "swept" not in mesh.info
    p = mesh.points_mm[mesh.tets]
    volume = np.abs(np.einsum("ij,ij->i", np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), p[:, 3] - p[:, 0])).sum() / 6
    assert volume == pytest.approx(counterbored.Volume(), rel=0.01)


@pytest.mark.slow  # about 50 s: two meshes and two solves
def test_swept_and_free_3d_meshes_give_the_same_stiffness(tmp_path):
    """Two different meshes of the same part converge to the same k: agreement within 1 %."""
    solid, ifc = holed_annulus()
    swept = mesh_part(solid, ifc, 2.0, 4.0, cache_dir=tmp_path, elements_per_circle=16)
    free = mesh_part(solid, ifc, 2.0, 4.0, cache_dir=tmp_path, elements_per_circle=16, sweep=False)
    assert swept.info["swept"]["layers"] >= 4 and "swept" not in free.info
    k = [1.0 / solve_unit_torsion(m, 12e6, 0.48).hub_motion[5] for m in (swept, free)]
    assert k[0] == pytest.approx(k[1], rel=0.01)
