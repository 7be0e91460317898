"""Reading a torque path at the load torques (`fea.large_deflection`) on paths made here from a closed-form
curve T = A tanh(theta / B) (exact tangents, tensile strain 0.5 theta, compressive 0.2 theta), so every reading
has an exact value. The repeating loads are read against a cyclic limit of 0.3, the impact against 0.433."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from seadesign.fea.elements import element_mesh
from seadesign.design.materials import StrainLimits
from seadesign.fea.large_deflection import large_deflection
from seadesign.fea.results import columns
from seadesign.fea.path_events import stop_point
from seadesign.fea.contact import ContactSummary
from seadesign.fea.torque_path import PathEvent, PathPoint, TorquePath

A, B = 15.0, 0.8  # Nm, rad: initial stiffness A / B = 18.75 Nm/rad
LIMITS = StrainLimits(cyclic=0.3, single=0.433)


def _path(end_rad: float, reason: str, n: int = 41) -> TorquePath:
    emesh = element_mesh(np.array([[0, 0, 0], [1e-3, 0, 0], [0, 1e-3, 0], [0, 0, 2e-3]], float), np.array([[0, 1, 2, 3]]), 2)
    theta = np.linspace(0.0, end_rad, n)
    points = tuple(PathPoint(float(t), A * math.tanh(t / B), A / B / math.cosh(t / B) ** 2, 0.5 * t, math.inf, 3,
                             (1e-9,), 0, 0.2 * t, 0, 2e6 * t, 0) for t in theta)
    stop = stop_point(list(points), reason, 1e9, 0.1)
    return TorquePath(points, reason, *stop, np.zeros((len(emesh.nodes_m), 3)), emesh, 2, 1.5)


def _theta(torque: float) -> float:
    return B * math.atanh(torque / A)


def test_loads_reached_are_read_from_the_curve():
    ld = large_deflection(_path(1.5, "target_reached"), 2.0, 11.7, 14.0, LIMITS)
    # Hermite between points 0.0375 rad apart: measured 3e-7 rad at most
    for point, torque in ((ld.standing, 2.0), (ld.stall, 11.7), (ld.impact, 14.0)):
        assert point.reached and point.rotation_rad == pytest.approx(_theta(torque), abs=1e-6)
        assert point.secant_k_Nm_per_rad == pytest.approx(torque / _theta(torque), rel=1e-5)
        assert point.tangent_k_Nm_per_rad == pytest.approx(A / B * (1 - (torque / A) ** 2), rel=2e-3)  # linear interp
        assert point.tensile_strain == pytest.approx(0.5 * _theta(torque), rel=1e-5)
        assert point.compressive_strain == pytest.approx(0.2 * _theta(torque), rel=1e-5)
        limit = 0.433 if point is ld.impact else 0.3
        assert point.strain_limit == limit
        assert point.strain_margin == pytest.approx(limit / (0.5 * _theta(torque)), rel=1e-5)
    # standing: 0.054 of 0.3; stall: 0.5 x 0.836 = 0.418 > 0.3 cyclic; impact: 0.5 x 1.345 = 0.672 > 0.433
    assert ld.standing.survives and not ld.stall.survives and not ld.impact.survives
    assert ld.cyclic_limit_rotation_rad == pytest.approx(0.6, abs=1e-9)
    assert ld.cyclic_limit_torque_Nm == pytest.approx(A * math.tanh(0.6 / B), rel=1e-3)
    assert ld.single_limit_rotation_rad == pytest.approx(0.866, abs=1e-9)
    assert ld.single_limit_torque_Nm == pytest.approx(A * math.tanh(0.866 / B), rel=1e-3)
    assert ld.peak_tensile_strain == pytest.approx(0.75) and ld.peak_compressive_strain == pytest.approx(0.3)
    assert ld.peak_von_mises_MPa == pytest.approx(3.0)
    assert math.isnan(ld.contact_rotation_rad) and ld.increments == 40 and ld.newton_iterations == 123


def test_a_load_past_the_stop_is_not_extrapolated():
    path = _path(0.5, "contact")  # stops at 0.5 rad, 8.29 Nm: below the stall torque
    ld = large_deflection(path, 2.0, 11.7, 14.0, LIMITS)
    assert ld.contact_rotation_rad == 0.5 and ld.contact_torque_Nm == pytest.approx(A * math.tanh(0.5 / B))
    assert ld.standing.survives
    for point in (ld.stall, ld.impact):
        assert not point.reached and not point.survives and math.isnan(point.rotation_rad)


def test_through_contact_the_event_names_first_contact_and_the_loads_their_share():
    # the same curve, gone on through contact from 0.3 rad: the pairs' moment grows as 2 (theta - 0.3) Nm, the
    # pressure as 10 (theta - 0.3) MPa; contact is read from the event, not the stop
    base = _path(1.5, "target_reached")
    points = tuple(replace(p, contact=ContactSummary(1e-6, 1e7 * (p.rotation_rad - 0.3), (1.0, 2.0, 3.0),
                                                     2 * (p.rotation_rad - 0.3), 1e-6))
                   if p.rotation_rad > 0.3 else p for p in base.points)
    event = PathEvent("contact", 0.3, A * math.tanh(0.3 / B), (1.0, 2.0, 3.0))
    ld = large_deflection(replace(base, points=points, events=(event,)), 2.0, 11.7, 14.0, LIMITS)
    assert ld.stop_reason == "target_reached" and ld.contact_rotation_rad == 0.3
    assert ld.contact_torque_Nm == event.torque_Nm and (ld.contact_at.x_mm, ld.contact_at.z_mm) == (1.0, 3.0)
    assert ld.peak_contact_pressure_MPa == pytest.approx(12.0)
    assert ld.standing.contact_share == 0.0  # 2 Nm: before contact
    for point, torque in ((ld.stall, 11.7), (ld.impact, 14.0)):  # points 0.0375 rad apart: linear interpolation
        assert point.contact_share == pytest.approx(2 * (_theta(torque) - 0.3) / torque, rel=1e-3)


@pytest.mark.parametrize("kind", ["contact_unconverged", "unresolved_penetration", "contact_energy_loss"])
def test_a_path_that_contact_ends_unconverged_says_why_and_where(kind):
    # the curve ends unconverged at 0.6 rad (11.6 Nm, short of the stall torque) after contact at 0.3 rad; the
    # increment tried to 0.61 rad failed where the event says
    events = (PathEvent("contact", 0.3, A * math.tanh(0.3 / B), (1.0, 2.0, 3.0)),
              PathEvent(kind, 0.61, math.nan, (4.0, 5.0, 6.0)))
    ld = large_deflection(replace(_path(0.6, "unconverged"), events=events), 2.0, 11.7, 14.0, LIMITS)
    assert ld.stop_reason == "unconverged" and not ld.stall.reached and not ld.stall.survives
    assert ld.unconverged_cause == kind and ld.unconverged_rotation_rad == 0.61
    assert (ld.unconverged_at.x_mm, ld.unconverged_at.y_mm, ld.unconverged_at.z_mm) == (4.0, 5.0, 6.0)
    plain = large_deflection(replace(_path(0.6, "unconverged"), events=events[:1]), 2.0, 11.7, 14.0, LIMITS)
    assert plain.unconverged_cause == "" and math.isnan(plain.unconverged_rotation_rad)  # Newton failed before contact
    assert math.isnan(plain.unconverged_at.x_mm)


def test_columns_keep_words_flags_and_curves():
    ld = large_deflection(_path(0.5, "contact", n=3), 2.0, 11.7, 14.0, StrainLimits(None, None))
    c = columns(ld, "large_")
    assert c["large_stop_reason"] == "contact" and c["large_stall_survives"] is False
    assert c["large_curve_rotation_rad"] == [0.0, 0.25, 0.5] and math.isnan(c["large_stall_strain_margin"])
    assert c["large_standing_survives"] is False  # no sourced limit: survival cannot be judged, so not claimed
    assert c["large_curve_tangent_Nm_per_rad"][0] == pytest.approx(A / B)


def test_torque_and_rotation_at_are_inverse_readings_of_the_curve():
    path = _path(1.5, "target_reached")
    for theta in (0.013, 0.4, 1.49):
        # cubic Hermite with exact tangents, points 0.0375 rad apart: measured 7.7e-7 Nm at most
        assert path.torque_at(theta) == pytest.approx(A * math.tanh(theta / B), abs=2e-6)
        assert path.rotation_at(path.torque_at(theta)) == pytest.approx(theta, abs=1e-12)
    assert path.torque_at(1.6) is None and path.rotation_at(A) is None
