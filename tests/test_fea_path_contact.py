"""The rotation path through frictionless self-contact, on the default study's 3 beams x 8 mm on a 4x coarser
one-layer mesh (4.2k tetrahedra): its notch closes near 0.32 rad. References: the path without contact forces
(the same equilibria before contact), the work of the hub torque (frictionless contact stores no energy of its
own), unloading (a frictionless elastic part retraces its loading curve) and the penetration tolerance."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from seadesign.errors import SolverError
from seadesign.fea.contact import ContactSettings
from seadesign.fea.finite_strain import Solid
from seadesign.fea.rotation_path import PathSettings, rotation_path, rotation_sweep, through_contact

END_RAD = 0.42


@pytest.fixture(scope="module")
def candidate(tmp_path_factory):
    from seadesign.design.study import load_study
    from seadesign.run.cache import Cache
    from seadesign.sweep.stages import tetrahedralize

    study = load_study()
    checked, part = study.check(study.candidate(beam_count=3, beam_thickness_mm=8.0))
    mesh = tetrahedralize(study, checked, part, Cache(tmp_path_factory.mktemp("cache")), coarsening=4.0, layers=1)
    return mesh, study.material.law


def _path(candidate, **settings):
    """The path with the sweep's settings through contact (`through_contact`), `settings` replaced."""
    mesh, law = candidate
    contact = settings.pop("contact", ContactSettings())
    swept = through_contact(PathSettings(max_rotation_rad=END_RAD, **settings))
    return rotation_path(mesh, law, 100.0, replace(swept, contact=contact))


@pytest.fixture(scope="module")
def through(candidate):
    return _path(candidate)


def _work(path) -> float:
    """The hub torque's work (J): the integral of the cubic Hermite curve through the points (exact for it)."""
    return sum((b.rotation_rad - a.rotation_rad) / 2 * (a.torque_Nm + b.torque_Nm)
               + (b.rotation_rad - a.rotation_rad) ** 2 / 12 * (a.tangent_Nm_per_rad - b.tangent_Nm_per_rad)
               for a, b in zip(path.points, path.points[1:]))


def test_the_path_goes_on_through_contact(through):
    assert through.stop_reason == "rotation_limit" and through.stop_rotation_rad == END_RAD
    (event,) = through.events
    assert event.kind == "contact" and 0.31 < event.rotation_rad < 0.32  # measured 0.3179 rad (the step landed at 0.32)
    last = through.points[-1].contact
    assert last.area_m2 > 1e-6 and last.peak_pressure_Pa > 1e6 and last.moment_Nm > 0.05  # measured 1.9 mm^2, 13 MPa, 0.24 Nm
    tolerance_m = ContactSettings().penetration_tol_mm * 1e-3
    assert all(p.contact.penetration_m <= tolerance_m for p in through.points)
    before = [p for p in through.points if p.rotation_rad < event.rotation_rad]
    assert all(p.contact.area_m2 == 0 for p in before) and through.points[len(before)].contact.area_m2 > 0


def test_frictionless_contact_stores_no_energy(candidate, through):
    # the hub's work equals the strain energy at the end: measured 1.1e-5 of it (the rest is the contact force times
    # the penetration the tolerance allows, and the curve's interpolation); without contact to the same rotation the
    # path's own balance is 3e-7
    mesh, law = candidate
    energy = Solid.of(through.emesh, law).energy(through.displacement_m)
    assert abs(_work(through) - energy) < 4e-5 * energy


def test_before_contact_the_path_is_the_one_without_contact_forces(candidate, through):
    # the path that stops at contact solves the same equilibria until then: its points lie on the through-contact
    # curve to the Hermite interpolation's error (measured 1.8e-5)
    stop = _path(candidate, contact=None)
    assert stop.stop_reason == "contact"
    for point in stop.points[1:]:
        assert through.torque_at(point.rotation_rad) == pytest.approx(point.torque_Nm, rel=1e-4)


@pytest.mark.slow
def test_the_torque_does_not_depend_on_the_penalty(candidate, through):
    # a ten times tighter penetration tolerance moves the end torque by 4.5e-6 (measured)
    tight = _path(candidate, contact=ContactSettings(penetration_tol_mm=0.0005))
    assert tight.points[-1].torque_Nm == pytest.approx(through.points[-1].torque_Nm, rel=1e-4)


@pytest.mark.slow
def test_contact_that_cannot_be_resolved_ends_the_path_unconverged_saying_where(candidate):
    # one multiplier update against a tolerance of a picometre: no increment into contact is accepted
    path = _path(candidate, contact=ContactSettings(penetration_tol_mm=1e-9, max_augmentations=1), min_step_rad=0.005)
    assert path.stop_reason == "unconverged" and all(p.contact.area_m2 == 0 for p in path.points)
    event = path.events[-1]
    assert event.kind == "unresolved_penetration" and event.rotation_rad > path.stop_rotation_rad
    assert math.isnan(event.torque_Nm) and np.isfinite(event.at_mm).all()


@pytest.mark.slow
def test_unloading_retraces_loading(candidate):
    """Loaded through contact to 0.42 rad and unloaded in the same 0.03 rad steps, the hub torque retraces: out of
    contact to Newton's tolerance (measured 2.3e-8), in contact to the penetration tolerance's effect (at a 10x tighter
    tolerance, measured 1.4e-5; a multiplier that presses across a gap opening on unloading, which a test of the
    penetration alone passes, gave 3.2e-4)."""
    mesh, law = candidate
    up = [0.03 * k for k in range(1, 15)]
    points = rotation_sweep(mesh, law, up + up[-2::-1],
                            PathSettings(contact=ContactSettings(penetration_tol_mm=0.00045)))
    loading, unloading = points[1:len(up) + 1], points[len(up) + 1:][::-1]
    assert [p.rotation_rad for p in unloading] == up[:-1]
    assert any(p.contact.area_m2 > 0 for p in unloading)  # unloading starts in contact
    for down, load in zip(unloading, loading):
        bound = 4e-5 if load.contact.area_m2 > 0 else 1e-7
        assert down.torque_Nm == pytest.approx(load.torque_Nm, rel=bound)
    with pytest.raises(SolverError, match="non-zero"):
        rotation_sweep(mesh, law, [0.1, 0.0])


@pytest.mark.slow
@pytest.mark.parametrize("failure", ["contact_energy_loss", "contact_unconverged"])
def test_an_increment_that_fails_at_every_step_ends_the_path_saying_where(candidate, monkeypatch, failure):
    # past 0.35 rad every attempt made to fail (as where a fold loses energy, or Newton wanders in a crease, at every
    # step size): the increments past it are cut back to the smallest step from a point in contact (first contact
    # is at 0.318 rad), none is kept, and the path ends unconverged with the event there, the last attempt's step
    # between that smallest step and twice it (not `min_step_rad`, which holds only before contact)
    import seadesign.fea.rotation_path as rp

    if failure == "contact_energy_loss":
        balanced = rp.energy_balanced
        monkeypatch.setattr(rp, "energy_balanced",
                            lambda a, b, *energies: b.rotation_rad <= 0.35 and balanced(a, b, *energies))
    else:
        solve = rp._solve
        monkeypatch.setattr(rp, "_solve", lambda p, u, v, previous, last, step, theta, *held: (
            lambda r: r if theta <= 0.35 else replace(r, status="failed"))(solve(p, u, v, previous, last, step, theta,
                                                                                 *held)))
    floor = 0.004
    path = _path(candidate, contact_min_step_rad=floor)
    assert path.stop_reason == "unconverged" and path.points[-1].rotation_rad <= 0.35
    assert path.points[-1].rotation_rad > 0.35 - 2 * floor  # cut back until the step is below the smallest
    assert path.points[-1].contact.area_m2 > 0
    event = path.events[-1]
    assert event.kind == failure and 0.35 < event.rotation_rad < 0.35 + 2 * floor
    assert floor <= event.rotation_rad - path.points[-1].rotation_rad < 2 * floor
    assert math.isnan(event.torque_Nm) and np.isfinite(event.at_mm).all()
