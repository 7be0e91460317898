"""The default study's headline numbers, each against an independent reference: which candidates
are valid (a separate 2-D computation of the beams' clearance and of the fillets' fit, from the
part's definition, not from the CAD), and the stiffest and softest k (CalculiX on the same mesh).
When the code changes one of them, this fails and the docs (`docs/results/default-sweep.md`) are updated
on purpose."""

from __future__ import annotations

import math

import numpy as np
import pytest
from shapely.geometry import Polygon

from seadesign.design.study import load_study

VALID_COUNT = 18  # docs/results/default-sweep.md: "18 of 24 candidates are valid"
K_HEADLINE = {(3, 4.0): 7.848, (6, 8.0): 33.33}  # the docs' k range, Nm/rad (softest, stiffest)


def _half_annulus(centre, r_in, r_out, normal, n=1500):
    """The part of an annulus about `centre` on the side of `normal`, as a fine polygon (mm)."""
    base = math.atan2(normal[1], normal[0])
    t = np.linspace(base - math.pi / 2, base + math.pi / 2, n)
    outer = np.c_[centre[0] + r_out * np.cos(t), centre[1] + r_out * np.sin(t)]
    inner = np.c_[centre[0] + r_in * np.cos(t[::-1]), centre[1] + r_in * np.sin(t[::-1])]
    return Polygon(np.vstack([outer, inner]))


def _beam(p, i):
    """Beam i of the definition (the Bit-Bots family, as measured from their `sea_ninjaflex.stl`): two opposed
    half-annuli of width t about points on the hub circle and on the ring's inner circle, clipped to the gap
    between them."""
    phi = math.radians(p.first_beam_angle_deg + 360.0 * i / p.beam_count)
    e = np.array([math.cos(phi), math.sin(phi)])
    normal = np.array([-e[1], e[0]]) * (-1 if p.clockwise else 1)
    w = p.beam_thickness_mm / 2
    first = _half_annulus(p.hub_radius_mm * e, p.arc_radius_mm - w, p.arc_radius_mm + w, normal)
    second = _half_annulus(p.ring_inner_radius_mm * e, p.arc_radius_mm - w, p.arc_radius_mm + w, -normal)
    gap = _half_annulus((0, 0), p.hub_radius_mm, p.ring_inner_radius_mm, e, n=3000).union(
        _half_annulus((0, 0), p.hub_radius_mm, p.ring_inner_radius_mm, -e, n=3000))
    return first.union(second).intersection(gap)


def independent_verdict(p, rules) -> bool:
    beams = [_beam(p, i) for i in range(p.beam_count)]
    clearance = min(beams[i].distance(beams[(i + 1) % len(beams)]) for i in range(len(beams)))
    notch = p.arc_radius_mm - p.beam_thickness_mm / 2  # a beam's inner side, centred on the hub / ring circle
    return clearance >= rules.min_clearance_mm and p.fillet_radius_mm < notch / 2


@pytest.mark.slow
def test_valid_candidates_agree_with_an_independent_clearance_computation():
    study = load_study()
    ours = {c.name: study.check(c)[0].valid for c in study.candidates()}
    theirs = {c.name: independent_verdict(c.params, study.validity) for c in study.candidates()}
    assert ours == theirs
    assert sum(ours.values()) == VALID_COUNT


@pytest.mark.slow
@pytest.mark.parametrize("beams, thickness", list(K_HEADLINE))
def test_headline_k_agrees_with_calculix_on_the_same_mesh(tmp_path, ccx, beams, thickness):
    from seadesign.fea.ccx import run_ccx, write_load_case_decks
    from seadesign.fea.loadcases import analyse
    from seadesign.run.cache import Cache
    from seadesign.sweep.stages import tetrahedralize

    study = load_study()
    m = study.material
    candidate, part = study.check(study.candidate(beams, thickness))
    mesh = tetrahedralize(study, candidate, part, Cache(tmp_path))  # the sweep's default mesh
    a = analyse(mesh, m.youngs_modulus_Pa, m.poisson_ratio, m.yield_strength_Pa, 1.0, 1.0, study.bearing_radius_mm)
    deck = write_load_case_decks(tmp_path / "ccx", a.unit, m.youngs_modulus_Pa, m.poisson_ratio, 1.0, 1.0)["stall"]
    k_ccx = 1.0 / run_ccx(deck, len(a.unit.emesh.nodes_m), timeout_s=1800).rotation_rad
    assert a.results.k_Nm_per_rad == pytest.approx(k_ccx, rel=5e-7)
    assert k_ccx == pytest.approx(K_HEADLINE[(beams, thickness)], rel=1e-3)  # the docs' digits
