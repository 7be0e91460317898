"""Beam-root fillets: every root corner gets a fillet of exactly the requested radius (counted on
the built profile), each adding the area the closed form gives for its corner, or the candidate
is invalid with the reason and the largest radius that fits."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from seadesign.design.geometry import build_part
from seadesign.design.study import load_study


@pytest.fixture(scope="module")
def study():
    return load_study()


def _circle_intersections(a, ra, b, rb):
    d = np.linalg.norm(b - a)
    x = (d**2 + ra**2 - rb**2) / (2 * d)
    h = math.sqrt(max(ra**2 - x**2, 0.0))
    u = (b - a) / d
    n = np.array([-u[1], u[0]])
    return [a + x * u + h * n, a + x * u - h * n]


def _arc_term(o, p, q):
    """Green's-theorem term 1/2 [O x (Q - P) + r^2 dtheta] of the short arc from P to Q about O."""
    r = np.linalg.norm(p - o)
    dtheta = (math.atan2(*(q - o)[::-1]) - math.atan2(*(p - o)[::-1]) + math.pi) % (2 * math.pi) - math.pi
    return 0.5 * (o[0] * (q - p)[1] - o[1] * (q - p)[0] + r * r * dtheta)


def expected_corners(p, rho):
    """Every root corner of the part, from its definition (the Bit-Bots family of `sea_ninjaflex.stl`):
    (corner xy, area in mm^2 between the fillet of radius rho and the two circles it is tangent to)."""
    out = []
    w = p.beam_thickness_mm / 2
    for i in range(p.beam_count):
        phi = math.radians(p.first_beam_angle_deg + 360.0 * i / p.beam_count)
        e = np.array([math.cos(phi), math.sin(phi)])
        normal = np.array([-e[1], e[0]]) * (-1 if p.clockwise else 1)  # the first arc's half-plane
        for root_r, centre_r, half, gap_outside_root in ((p.hub_radius_mm, p.hub_radius_mm, 1, True),
                                                         (p.ring_inner_radius_mm, p.ring_inner_radius_mm, -1, False)):
            c = centre_r * e
            for side_r, gap_outside_side in ((p.arc_radius_mm + w, True), (p.arc_radius_mm - w, False)):
                corner = max(_circle_intersections(np.zeros(2), root_r, c, side_r),
                             key=lambda v: half * np.dot(v - c, normal))
                ra = root_r + (rho if gap_outside_root else -rho)
                rb = side_r + (rho if gap_outside_side else -rho)
                f = min(_circle_intersections(np.zeros(2), ra, c, rb), key=lambda q: np.linalg.norm(q - corner))
                t1 = root_r * f / np.linalg.norm(f)
                t2 = c + side_r * (f - c) / np.linalg.norm(f - c)
                area = abs(_arc_term(np.zeros(2), corner, t1) + _arc_term(f, t1, t2) + _arc_term(c, t2, corner))
                out.append((corner, area))
    return out


@pytest.mark.parametrize("n, t, rho", [(3, 4.0, 1.25), (5, 6.0, 0.75), (8, 4.0, 1.0), (4, 8.0, 0.45), (7, 6.0, 0.45)])
def test_every_root_corner_gets_its_fillet_and_the_closed_form_area(study, n, t, rho):
    p = dataclasses.replace(study.candidate(n, t).params, fillet_radius_mm=rho)
    part = build_part(p)
    assert not part.errors, part.errors
    arcs = [e for e in part.profile.Edges() if e.geomType() == "CIRCLE" and abs(e.radius() - rho) < 1e-9]
    assert len(arcs) == 4 * n == len(part.fillets)
    added = part.profile.cut(part.raw_profile).Faces()  # one piece of material per rounded corner
    assert len(added) == 4 * n
    corners = expected_corners(p, rho)
    for face in added:
        centre = np.array([face.Center().x, face.Center().y])
        corner, area = min(corners, key=lambda ca: np.linalg.norm(ca[0] - centre))
        assert np.linalg.norm(corner - centre) < 2 * rho
        assert face.Area() == pytest.approx(area, rel=1e-6), corner
    total = sum(a for _, a in corners)
    assert part.profile.Area() - part.raw_profile.Area() == pytest.approx(total, rel=1e-6)


@pytest.mark.parametrize("t, rho", [(6.0, 1.0), (8.0, 0.75), (4.0, 1.5)])
def test_a_fillet_that_does_not_fit_makes_the_candidate_invalid(study, t, rho):
    # a beam's inner side (radius arc - t/2) is centred on the hub or ring circle: the notch where it
    # meets them takes a fillet only below half that radius
    p = dataclasses.replace(study.candidate(3, t).params, fillet_radius_mm=rho)
    limit = (p.arc_radius_mm - t / 2) / 2
    part = build_part(p)
    assert part.solid is None and len(part.errors) == 1
    assert f"the {rho:g} mm root fillet does not fit" in part.errors[0]
    largest = float(part.errors[0].rsplit("is ", 1)[1].split(" mm")[0])
    assert limit - 2e-3 <= largest <= limit
    reasons = study.check(dataclasses.replace(study.candidate(3, t), params=p))[0].reasons
    assert any("root fillet does not fit" in r for r in reasons)
