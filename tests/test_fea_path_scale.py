"""A path under a scaled law, read from the path computed once, against the path solved under that law: a thin
annular plate in torsion (it buckles: a stop no scale moves) and the same plate driven to a target torque."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from helpers_annulus import E, annulus_mesh

from seadesign.design.materials import Hyperelastic, load_material
from seadesign.fea.path_scale import scaled_path
from seadesign.fea.rotation_path import PathSettings, rotation_path

SETTINGS = PathSettings(max_step_rad=0.05)
LAW = Hyperelastic.from_linear(E, 0.45)
TARGET_NM = 50.0  # far above what the plate carries: it stops where it buckles


def _times(law: Hyperelastic, s: float) -> Hyperelastic:
    """The law with every modulus times s, written apart from `Material.scaled`."""
    return replace(law, c10_Pa=law.c10_Pa * s, d1_per_Pa=law.d1_per_Pa / s)


@pytest.fixture(scope="module")
def plate():
    mesh = annulus_mesh(10.0, 20.0, 0.3, 4, 48, 1)
    return mesh, rotation_path(mesh, LAW, TARGET_NM, SETTINGS)


def _same(scaled, solved) -> None:
    """The same points and stop: to round-off where Newton takes the same iterates; scales that are not powers of
    two change the last digits of the iterates (measured up to 1e-11 relative in the peak stress and strain)."""
    assert scaled.stop_reason == solved.stop_reason
    assert len(scaled.points) == len(solved.points)
    for a, b in zip(scaled.points, solved.points):
        assert a.rotation_rad == pytest.approx(b.rotation_rad, rel=1e-12, abs=1e-15)
        assert a.peak_tensile_strain == pytest.approx(b.peak_tensile_strain, rel=1e-10, abs=1e-15)
        for x, y in ((a.torque_Nm, b.torque_Nm), (a.tangent_Nm_per_rad, b.tangent_Nm_per_rad),
                     (a.peak_von_mises_Pa, b.peak_von_mises_Pa)):
            assert x == pytest.approx(y, rel=1e-10, abs=1e-15)
    assert scaled.stop_rotation_rad == pytest.approx(solved.stop_rotation_rad, rel=1e-10)
    assert scaled.stop_torque_Nm == pytest.approx(solved.stop_torque_Nm, rel=1e-10)


@pytest.mark.parametrize("s", [0.37, 2.9])
def test_a_stop_no_scale_moves_is_the_scaled_laws_stop(plate, s):
    mesh, base = plate
    assert base.stop_reason == "bifurcation" and s * base.stop_torque_Nm < TARGET_NM
    _same(scaled_path(base, s, TARGET_NM, SETTINGS.contact_gap_mm), rotation_path(mesh, _times(LAW, s), TARGET_NM, SETTINGS))


def test_a_stiffer_law_stops_at_the_target_where_its_own_path_does(plate):
    mesh, base = plate
    target = 1.2 * base.stop_torque_Nm  # reached by the scaled curve before the buckling the base path stops at
    scaled = scaled_path(base, 2.3, target, SETTINGS.contact_gap_mm)
    assert scaled.stop_reason == "target_reached" and len(scaled.points) < len(base.points)
    _same(scaled, rotation_path(mesh, _times(LAW, 2.3), target, SETTINGS))
    assert scaled.displacement_m is None  # cut short: its last state is not the base path's


def test_a_path_cut_at_the_target_is_the_path_solved_to_the_target_over_the_scale_to_the_last_digit(plate):
    mesh, base = plate
    target, s = 1.2 * base.stop_torque_Nm, 2.3
    short = rotation_path(mesh, LAW, target / s, SETTINGS)
    assert short.stop_reason == "target_reached" and len(short.points) < len(base.points)
    a, b = (scaled_path(p, s, target, SETTINGS.contact_gap_mm) for p in (base, short))
    assert repr((a.points, a.stop_reason, a.stop_rotation_rad, a.stop_torque_Nm, a.events)) == \
        repr((b.points, b.stop_reason, b.stop_rotation_rad, b.stop_torque_Nm, b.events))  # floats by repr: exact, NaN too


def test_a_softer_law_cannot_read_a_path_that_stopped_at_its_target(plate):
    mesh, base = plate
    short = rotation_path(mesh, LAW, 0.5 * base.stop_torque_Nm, SETTINGS)
    assert short.stop_reason == "target_reached"
    assert scaled_path(short, 0.5, 0.5 * base.stop_torque_Nm, SETTINGS.contact_gap_mm) is None
    assert scaled_path(short, 1.5, 0.5 * base.stop_torque_Nm, SETTINGS.contact_gap_mm) is not None


def test_a_scaled_path_keeps_its_snapshot_only_where_the_scaled_path_would(plate):
    mesh, base = plate
    stall = 0.5 * base.stop_torque_Nm
    shot = rotation_path(mesh, LAW, TARGET_NM, SETTINGS, snapshot_torque_Nm=stall)
    assert 0 < shot.snapshot_index < len(shot.points) - 1
    assert scaled_path(shot, 0.5, TARGET_NM, SETTINGS.contact_gap_mm, stall) is None  # carried later, if at all
    near = 1.0 + 1e-6  # the same point still carries the stall torque first
    assert scaled_path(shot, near, TARGET_NM, SETTINGS.contact_gap_mm, stall).snapshot_index == shot.snapshot_index


def test_a_scale_is_recognised_only_where_every_modulus_scales():
    ninjaflex = load_material("ninjaflex")
    soft = ninjaflex.scaled(0.4, "test")
    assert soft.scaled_from is ninjaflex and soft.scaled(2.0, "again").scaled_from is ninjaflex
    assert soft.law.scale_of(ninjaflex.law) == pytest.approx(0.4, rel=1e-15)
    assert _times(LAW, 3.0).scale_of(LAW) == pytest.approx(3.0, rel=1e-15)
    assert replace(_times(LAW, 3.0), d1_per_Pa=LAW.d1_per_Pa).scale_of(LAW) is None  # the bulk modulus kept
    shaped = Hyperelastic("mooney_rivlin", LAW.c10_Pa / 2, LAW.d1_per_Pa, "test", c01_Pa=LAW.c10_Pa / 2)
    assert shaped.scale_of(LAW) is None and shaped.shear_modulus_Pa == pytest.approx(LAW.shear_modulus_Pa)
    assert np.isfinite(soft.youngs_modulus_Pa) and soft == replace(soft, scaled_from=None)  # not part of equality
