"""Geometry and validity: volumes against hand computation and an independent point-membership
integration, validity verdicts on known-good and known-bad parameter sets, STL read-back."""

import dataclasses
import math

import numpy as np
import pytest
import trimesh

from seadesign.design.candidate import Candidate
from seadesign.design.export import write_step, write_stl
from seadesign.design.geometry import build_part
from seadesign.design.params import BoltPattern, GeometryParams
from seadesign.design.study import load_study
from seadesign.design.validity import check


@pytest.fixture(scope="module")
def study():
    return load_study()


def _plain(study, **changes) -> GeometryParams:
    """A default-study candidate with changes (e.g. no fillet)."""
    return dataclasses.replace(study.candidate(5, 6.0).params, **changes)


def test_zero_beams_volume_is_hub_plus_ring_by_hand(study):
    p = _plain(study, beam_count=0)
    part = build_part(p)
    t = p.thickness_mm
    hub = math.pi * (p.hub_radius_mm**2 - p.bore_radius_mm**2) * t
    ring = math.pi * (p.ring_outer_radius_mm**2 - p.ring_inner_radius_mm**2) * t
    holes = sum(math.pi * h.radius_mm**2 * t for h in p.hub_bolts.holes() + p.ring_bolts.holes())
    assert part.volume_mm3 == pytest.approx(hub + ring - holes, rel=1e-6)
    # hub and ring alone are two bodies: not a spring
    assert any("2 separate solids" in r for r in check(part, study.validity))


def _inside_profile(p: GeometryParams, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Point membership of the unfilleted profile, written from the geometric definition."""
    r = np.hypot(x, y)
    inside = (r <= p.hub_radius_mm) | ((r >= p.ring_inner_radius_mm) & (r <= p.ring_outer_radius_mm))
    lo, hi = p.arc_radius_mm - p.beam_thickness_mm / 2, p.arc_radius_mm + p.beam_thickness_mm / 2
    in_gap = (r >= p.hub_radius_mm) & (r <= p.ring_inner_radius_mm)
    for i in range(p.beam_count):
        a = -math.radians(p.first_beam_angle_deg + 360.0 * i / p.beam_count)
        u, v = x * math.cos(a) - y * math.sin(a), x * math.sin(a) + y * math.cos(a)
        side1 = v <= 0 if p.clockwise else v >= 0
        d1 = np.hypot(u - p.hub_radius_mm, v)
        d2 = np.hypot(u - p.hub_radius_mm - 2 * p.arc_radius_mm, v)
        arc1 = (d1 >= lo) & (d1 <= hi) & side1
        arc2 = (d2 >= lo) & (d2 <= hi) & ~side1
        inside |= in_gap & (arc1 | arc2)
    return inside


@pytest.mark.parametrize("n, t", [(3, 4.0), (5, 6.0), (6, 8.0)])
def test_profile_area_matches_independent_integration(study, n, t):
    p = dataclasses.replace(study.candidate(n, t).params, fillet_radius_mm=0.0)
    part = build_part(p)
    h = 0.04  # mm grid
    g = np.arange(-p.ring_outer_radius_mm, p.ring_outer_radius_mm, h) + h / 2
    x, y = np.meshgrid(g, g)
    area = _inside_profile(p, x, y).sum() * h * h
    assert part.raw_profile.Area() == pytest.approx(area, rel=3e-3)


def test_profile_is_rotationally_symmetric_and_one_handed(study):
    p = dataclasses.replace(study.candidate(5, 6.0).params, fillet_radius_mm=0.0)
    g = np.linspace(-30, 30, 601)
    x, y = np.meshgrid(g, g)
    base = _inside_profile(p, x, y)
    a = 2 * math.pi / p.beam_count
    rotated = _inside_profile(p, x * math.cos(a) - y * math.sin(a), x * math.sin(a) + y * math.cos(a))
    mirrored = _inside_profile(p, x, -y)
    assert np.mean(base != rotated) < 1e-3  # every beam alike
    assert np.mean(base != mirrored) > 1e-2  # and not mirror-symmetric: one handedness
    # the CAD agrees with this membership function: a few hundred sample points
    part = build_part(p)
    import cadquery as cq

    rng = np.random.default_rng(0)
    pts = rng.uniform(-p.ring_outer_radius_mm, p.ring_outer_radius_mm, (300, 2))
    expected = _inside_profile(p, pts[:, 0], pts[:, 1])
    solid = cq.Solid.extrudeLinear(part.raw_profile, cq.Vector(0, 0, 1))
    got = np.array([solid.isInside(cq.Vector(px, py, 0.5)) for px, py in pts])
    assert np.mean(got == expected) > 0.99


def test_fillets_add_material_at_the_roots(study):
    sharp = build_part(_plain(study, fillet_radius_mm=0.0))
    round_ = build_part(_plain(study))
    extra = round_.volume_mm3 - sharp.volume_mm3
    r, t, corners = 1.0, 9.0, 4 * 5
    # each root corner gains less than a full square-minus-quarter-circle at a right angle or sharper
    assert 0 < extra
    assert extra < corners * (1 / math.tan(math.radians(10)) - math.pi / 2 + math.radians(10)) * r * r * t


def test_known_good_candidates_are_valid(study):
    for n, t in [(3, 4.0), (5, 6.0), (10, 4.0), (6, 8.0)]:
        c, part = study.check(study.candidate(n, t))
        assert c.valid, (n, t, c.reasons)
        assert part.solid.isValid()
        assert c.mass_kg == pytest.approx(part.volume_mm3 * 1e-9 * 1190.0)


@pytest.mark.parametrize("n, t", [(9, 6.0), (9, 8.0), (10, 8.0)])
def test_crowded_beams_touch(study, n, t):
    reasons = study.check(study.candidate(n, t))[0].reasons
    assert any("neighbouring beams" in r for r in reasons), reasons


def test_clearance_threshold_is_computed(study):
    # 7 x 8 mm leaves about 0.79 mm between beams: invalid at 0.8, valid at 0.7
    p = study.candidate(7, 8.0).params
    part = build_part(p)
    strict = check(part, study.validity)
    loose = check(part, dataclasses.replace(study.validity, min_clearance_mm=0.7))
    assert any("0.79 mm apart" in r for r in strict)
    assert not loose


def test_degenerate_tight_arc_is_invalid(study):
    # beam arc radius just above half the width: the inner arc shrinks to a tiny edge
    base = study.candidate(4, 8.0).params
    p = dataclasses.replace(base, arc_radius_mm=4.05,
                            ring_bolts=dataclasses.replace(base.ring_bolts, circle_diameter_mm=2 * (14 + 8.1 + 4)))
    reasons = study.check(Candidate((), p))[0].reasons
    assert any("degenerate feature" in r for r in reasons), reasons


def test_bolt_hole_cutting_a_gap_is_invalid(study):
    # ring holes pushed onto the ring's inner edge open into the gaps between beams
    p = _plain(study, ring_bolts=BoltPattern(8, 2 * 24.5, 3.2, 22.5))
    reasons = study.check(Candidate((), p))[0].reasons
    assert any("ring bolt hole" in r and "gap" in r for r in reasons), reasons


def test_stl_read_back_and_step(study, tmp_path):
    c, part = study.check(study.candidate(5, 6.0))
    stl = write_stl(part.solid, tmp_path / "part.stl", tolerance_mm=0.01)
    mesh = trimesh.load(stl, force="mesh")
    assert mesh.is_watertight and mesh.is_winding_consistent and mesh.volume > 0
    assert mesh.volume == pytest.approx(c.volume_mm3, rel=5e-3)
    assert np.allclose(mesh.bounds[:, 2], [0.0, 9.0], atol=1e-6)  # mm, axis +z
    step = write_step(part.solid, tmp_path / "part.step")
    assert step.read_text(errors="ignore").startswith("ISO-10303-21")


def test_sliver_gaps_are_detected(study):
    # 6 x 8 mm gaps taper into long slits where the outer arcs meet the ring almost tangentially;
    # 5 x 6 mm gaps have no such slit. A printer that cannot keep 1.5 mm slits open fuses the first.
    rules = dataclasses.replace(study.validity, min_feature_mm=1.5)
    slit = check(build_part(study.candidate(6, 8.0).params), rules)
    open_ = check(build_part(study.candidate(5, 6.0).params), rules)
    assert any(r.startswith("sliver") for r in slit), slit
    assert not any(r.startswith("sliver") for r in open_), open_
