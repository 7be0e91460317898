"""Meshing: named boundaries, cache, bounds and errors, on small CadQuery parts."""

from __future__ import annotations

import numpy as np
import pytest
from helpers_parts import holed_annulus

from seadesign.errors import MeshError
from seadesign.mesh import mesh_part
from seadesign.mesh.tetmesh import boundary_facets
from seadesign.design.interfaces import Interfaces

@pytest.fixture(scope="module")
def part():
    return holed_annulus()


def test_boundaries_are_named_boundary_facets_on_their_cylinders(part, tmp_path):
    solid, ifc = part
    mesh = mesh_part(solid, ifc, elements_across_beam=2, beam_width_mm=4.0, cache_dir=tmp_path)
    expected = {"bore", "outer"} | {f"hub_hole_{i}" for i in range(4)} | {f"ring_hole_{i}" for i in range(6)}
    assert set(mesh.boundaries) == expected
    # every named facet belongs to exactly one tetrahedron (checked independently of the mesher's output)
    local = np.array([[1, 2, 3], [0, 3, 2], [0, 1, 3], [0, 2, 1]])
    all_faces = np.sort(mesh.tets[:, local].reshape(-1, 3), axis=1)
    keys, counts = np.unique(all_faces, axis=0, return_counts=True)
    single = {tuple(k) for k in keys[counts == 1]}
    holes = {"bore": (0.0, 0.0, 3.0), "outer": (0.0, 0.0, 20.0)}
    holes.update({f"hub_hole_{i}": (h.x_mm, h.y_mm, h.radius_mm) for i, h in enumerate(ifc.hub_holes)})
    holes.update({f"ring_hole_{i}": (h.x_mm, h.y_mm, h.radius_mm) for i, h in enumerate(ifc.ring_holes)})
    for name, idx in mesh.boundaries.items():
        faces = mesh.boundary_faces[idx]
        assert all(tuple(f) in single for f in np.sort(faces, axis=1))
        cx, cy, r = holes[name]
        d = np.hypot(mesh.points_mm[faces][..., 0] - cx, mesh.points_mm[faces][..., 1] - cy)
        np.testing.assert_allclose(d, r, atol=1e-3)
        # the wall is covered: facet area ~ 2 pi r t (polygonal, so slightly less)
        tri = mesh.points_mm[faces]
        area = 0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1).sum()
        assert area == pytest.approx(2 * np.pi * r * 5.0, rel=0.1)
    assert len(boundary_facets(mesh.tets)) == len(mesh.boundary_faces)
    assert mesh.quality.n_tets == len(mesh.tets) and mesh.quality.min_dihedral_deg > 1.0


def test_cache_returns_the_identical_mesh(part, tmp_path):
    solid, ifc = part
    first = mesh_part(solid, ifc, 2, 4.0, cache_dir=tmp_path)
    again = mesh_part(solid, ifc, 2, 4.0, cache_dir=tmp_path)
    assert not first.info["cache_hit"] and again.info["cache_hit"]
    np.testing.assert_array_equal(first.points_mm, again.points_mm)
    np.testing.assert_array_equal(first.tets, again.tets)
    other = mesh_part(solid, ifc, 2.5, 4.0, cache_dir=tmp_path)
    assert other.info["cache_key"] != first.info["cache_key"]


def test_gmsh_is_deterministic_without_cache(part, tmp_path):
    solid, ifc = part
    a = mesh_part(solid, ifc, 2, 4.0, cache_dir=tmp_path / "a")
    b = mesh_part(solid, ifc, 2, 4.0, cache_dir=tmp_path / "b")
    np.testing.assert_array_equal(a.tets, b.tets)


def test_pytetwild_backend_meshes_the_tessellated_solid(part, tmp_path):
    solid, ifc = part
    mesh = mesh_part(solid, ifc, 1.5, 4.0, cache_dir=tmp_path, backend="pytetwild", epsilon=2e-3)
    assert {"bore", "outer", "hub_hole_0", "ring_hole_5"} <= set(mesh.boundaries)
    vol = np.abs(np.linalg.det(mesh.points_mm[mesh.tets[:, 1:]] - mesh.points_mm[mesh.tets[:, :1]])).sum() / 6
    assert vol == pytest.approx(solid.Volume(), rel=0.01)


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"elements_across_beam": 0}, "must be positive"),
        ({"backend": "netgen"}, "unknown"),
        ({"max_tets": 10}, "max_tets"),
    ],
)
def test_bad_settings_raise_clear_errors(part, tmp_path, kwargs, message):
    solid, ifc = part
    args = {"elements_across_beam": 2, "beam_width_mm": 4.0, "cache_dir": tmp_path, **kwargs}
    with pytest.raises(MeshError, match=message):
        mesh_part(solid, ifc, **args)


def test_time_limit_gives_up_with_a_clear_error(part, tmp_path):
    solid, ifc = part
    with pytest.raises(MeshError, match="failed 2 times"):
        mesh_part(solid, ifc, 2, 4.0, cache_dir=tmp_path, timeout_s=0.01, retries=1)


def test_gmsh_needs_a_solid(tmp_path):
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=float)
    f = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    with pytest.raises(MeshError, match="pytetwild"):
        mesh_part((v, f), Interfaces((), (), 0, 0, 0, 1, 1), 1, 1.0, cache_dir=tmp_path, backend="gmsh")
