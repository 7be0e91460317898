"""The Bit-Bots STL (mm, axis Y): loaded onto +z, interfaces detected, meshed with pytetwild, solved."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import shared_path

from seadesign.fea.loadcases import analyse
from seadesign.mesh import load_stl, mesh_part
from seadesign.mesh.detect import detect_interfaces

pytestmark = pytest.mark.shared


@pytest.fixture(scope="module")
def bitbots():
    v, f = load_stl(shared_path("data", "bitbots", "sea_ninjaflex.stl"), axis="y")
    return v, f, detect_interfaces(v, f)


def test_stl_is_rotated_onto_z_and_interfaces_match_the_drawing(bitbots):
    v, f, ifc = bitbots
    assert v[:, 2].min() == pytest.approx(0.0) and v[:, 2].max() == pytest.approx(9.0, abs=1e-6)
    assert np.hypot(v[:, 0], v[:, 1]).max() == pytest.approx(25.0, abs=0.05)
    # measured from the Bit-Bots STL: 4 x dia 2.7 on a 16 mm circle, 6 x dia 3.2 on a 44 mm circle, hub radius 11, ring inner 20
    assert len(ifc.hub_holes) == 4 and len(ifc.ring_holes) == 6
    assert all(np.hypot(h.x_mm, h.y_mm) == pytest.approx(8.0, abs=0.01) for h in ifc.hub_holes)
    assert all(h.radius_mm == pytest.approx(1.35, abs=0.02) for h in ifc.hub_holes)
    assert all(np.hypot(h.x_mm, h.y_mm) == pytest.approx(22.0, abs=0.01) for h in ifc.ring_holes)
    assert all(h.radius_mm == pytest.approx(1.6, abs=0.02) for h in ifc.ring_holes)
    assert ifc.hub_radius_mm == pytest.approx(11.0, abs=0.5)
    assert ifc.ring_inner_radius_mm == pytest.approx(20.0, abs=0.5)


def test_bitbots_part_meshes_and_solves(bitbots, tmp_path):
    v, f, ifc = bitbots
    mesh = mesh_part((v, f), ifc, elements_across_beam=1.0, beam_width_mm=3.0, cache_dir=tmp_path,
                     backend="pytetwild", epsilon=2e-3)
    assert {f"hub_hole_{i}" for i in range(4)} | {f"ring_hole_{i}" for i in range(6)} <= set(mesh.boundaries)
    vol = np.abs(np.linalg.det(mesh.points_mm[mesh.tets[:, 1:]] - mesh.points_mm[mesh.tets[:, :1]])).sum() / 6
    assert vol == pytest.approx(10520, rel=0.02)  # the STL's own volume: 10,520 mm^3
    res = analyse(mesh, 12e6, 0.48, 4e6, 11.7, 27.7, bearing_radius_mm=ifc.hub_radius_mm).results.columns()
    assert res["equilibrium_rel_error"] < 1e-6
    assert res["k_Nm_per_rad"] > 0 and res["impact_bolt_count"] == 4
    # four bolts on an 8 mm radius carry the impact torque: about T / (4 r) each (each hole wall
    # also takes a small twisting moment of its own, so a little less)
    assert res["impact_reaction_per_bolt_N"] == pytest.approx(27.7 / (4 * 8e-3), rel=0.25)
