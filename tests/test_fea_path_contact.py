"""The rotation path through frictionless self-contact, on the default study's 3 beams x 8 mm on a 4x coarser
one-layer mesh (4.2k tetrahedra): its notches close from 0.30 rad. References: the path without contact forces
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
    # measured 0.3020 rad, where a Gauss point beside the notch's root presses on the face across the root (its
    # vertices are still 0.11 mm apart); the event is only as precise as the step that reaches it (0.295-0.305 rad)
    assert event.kind == "contact" and 0.29 < event.rotation_rad < 0.31
    last = through.points[-1].contact
    assert last.area_m2 > 1e-6 and last.peak_pressure_Pa > 1e6 and last.moment_Nm > 0.05  # measured 1.9 mm^2, 40 MPa, 0.46 Nm
    tolerance_m = ContactSettings().penetration_tol_mm * 1e-3
    assert all(p.contact.penetration_m <= tolerance_m for p in through.points)
    before = [p for p in through.points if p.rotation_rad < event.rotation_rad]
    assert all(p.contact.area_m2 == 0 for p in before) and through.points[len(before)].contact.area_m2 > 0


def test_frictionless_contact_stores_no_energy(candidate, through):
    # the hub's work equals the strain energy at the end: measured 1.6e-5 of it (the rest is the contact force times
    # the penetration the tolerance allows, and the curve's interpolation); without contact to the same rotation the
    # path's own balance is 3e-7
    mesh, law = candidate
    energy = Solid.of(through.emesh, law).energy(through.displacement_m)
    assert abs(_work(through) - energy) < 4e-5 * energy


def test_before_contact_the_path_is_the_one_without_contact_forces(candidate, through):
    # the path that stops where the vertices come within 0.1 mm solves the same equilibria until the first contact:
    # its points lie on the through-contact curve to the Hermite interpolation's error (measured 1.8e-5) where that
    # curve's interpolation does not reach across the contact's onset
    stop = _path(candidate, contact=None)
    assert stop.stop_reason == "contact"
    free = max(p.rotation_rad for p in through.points if p.contact.area_m2 == 0)
    before = [p for p in stop.points[1:] if p.rotation_rad <= free]
    assert len(before) >= 7
    for point in before:
        assert through.torque_at(point.rotation_rad) == pytest.approx(point.torque_Nm, rel=1e-4)


@pytest.mark.slow
@pytest.mark.parametrize("penalty_factor", [30.0, 300.0])
def test_the_torque_does_not_depend_on_the_penalty(candidate, through, penalty_factor):
    # a penalty 3.3 times softer or 3 times stiffer moves the end torque by 1.7e-5 and 2.3e-5 (measured)
    other = _path(candidate, contact=ContactSettings(penalty_factor=penalty_factor))
    assert other.points[-1].torque_Nm == pytest.approx(through.points[-1].torque_Nm, rel=1e-4)


@pytest.mark.slow
def test_the_torque_converges_with_the_penetration_tolerance(candidate, through):
    # a nine times tighter tolerance moves the end torque by 1.6e-4 (measured; 4.5e-6 before the pairs across a
    # notch's root were searched: those points start within 26 um of the face across, so 4.5 um is a larger share)
    tight = _path(candidate, contact=ContactSettings(penetration_tol_mm=0.0005))
    assert tight.points[-1].torque_Nm == pytest.approx(through.points[-1].torque_Nm, rel=4e-4)


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


def test_no_surface_point_sinks_into_a_face_it_faces(candidate, through):
    # brute force, apart from the contact search: every Gauss point of the boundary's faces against every flat facet
    # of a later face (the contact's one pass, `ContactSurface`) that it faces (normals opposed, the point in front of
    # it at rest) and projects inside at the end; none may lie deeper behind the facet's plane than the penetration
    # tolerance (within the search's 0.1 mm: deeper points entered from the side at a fold). Measured 4.3 um (the
    # tolerance 4.5 um); before the pairs across a notch's root were searched, points beside the roots sank up to
    # 10 um into the face across
    from scipy.spatial import cKDTree
    from seadesign.fea.contact import FACING_COSINE, ContactSurface
    from seadesign.fea.contact_geometry import FACE_WEIGHTS, SUBFACETS
    mesh, _ = candidate
    emesh, u = through.emesh, through.displacement_m
    surface = ContactSurface.of(emesh, mesh.boundary_faces, np.empty(0, dtype=np.int64))
    x, x0 = surface.nodes_m + u, surface.nodes_m
    points, rest = surface.points(u), surface.rest_points_m
    tri, tri0 = x[surface.facets], x0[surface.facets]

    def normals(t):
        n = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
        return n / np.linalg.norm(n, axis=1)[:, None]

    n, n0 = normals(tri), normals(tri0)
    corners = x[surface.faces[:, :3]]
    n_face = normals(corners)
    centroid = tri.mean(axis=1)
    reach = np.linalg.norm(tri - centroid[:, None], axis=2).max() + 1e-4
    deepest = 0.0
    for f, near in enumerate(cKDTree(points).query_ball_point(centroid, reach)):
        q = np.array(near, dtype=np.int64)
        q = q[q // len(FACE_WEIGHTS) < f // len(SUBFACETS)]  # one pass: a face's points against later faces' facets
        q = q[(n_face[q // len(FACE_WEIGHTS)] @ n[f] < FACING_COSINE) & ((rest[q] - tri0[f, 0]) @ n0[f] > 0)]
        gap = (points[q] - tri[f, 0]) @ n[f]
        e1, e2, d = tri[f, 1] - tri[f, 0], tri[f, 2] - tri[f, 0], points[q] - tri[f, 0] - gap[:, None] * n[f]
        a11, a12, a22 = e1 @ e1, e1 @ e2, e2 @ e2
        s, t = (a22 * (d @ e1) - a12 * (d @ e2)), (a11 * (d @ e2) - a12 * (d @ e1))
        det = a11 * a22 - a12**2
        inside = (s >= 0) & (t >= 0) & (s + t <= det)
        sunk = -gap[inside & (gap > -1e-4)]
        deepest = max(deepest, float(sunk.max(initial=0.0)))
    assert deepest <= 1.5 * ContactSettings().penetration_tol_mm * 1e-3
