"""Validity of a built candidate, computed from its geometry (never looked up).

A candidate is valid when it is one valid closed solid, neighbouring beams keep a printable
clearance, no edge or gap falls below the printable feature size, and every bolt hole keeps a
wall to the gaps and to the outer edges. Each failed check gives a precise reason.
"""

from __future__ import annotations

import math

import cadquery as cq
import numpy as np
from shapely.geometry import Point, Polygon

from seadesign.design.geometry import Part
from seadesign.design.params import ValidityRules


def _wire_polygon(wire: cq.Wire, step_mm: float = 0.05) -> np.ndarray:
    """Points (x, y) along a closed planar wire in its own order, spaced about `step_mm`."""
    n = max(16, int(math.ceil(wire.Length() / step_mm)))
    return np.array([(v.x, v.y) for v in wire.positions(np.linspace(0.0, 1.0, n, endpoint=False))])


def _gaps(part: Part) -> list[Polygon]:
    """The openings between beams in the (hole-free) profile, as polygons."""
    return [Polygon(_wire_polygon(w)) for face in part.profile.Faces() for w in face.innerWires()]


def beam_clearance_mm(part: Part) -> float:
    """Smallest distance between neighbouring beams (0 when they touch or overlap)."""
    beams = part.beams
    if len(beams) < 2:
        return math.inf
    return min(beams[i].distance(beams[(i + 1) % len(beams)]) for i in range(len(beams)))


def check(part: Part, rules: ValidityRules) -> list[str]:
    """All reasons the candidate is invalid; an empty list means valid."""
    params = part.params
    reasons: list[str] = list(part.errors)
    clearance = beam_clearance_mm(part)
    if clearance < rules.min_clearance_mm:
        word = "touch or overlap" if clearance < 1e-6 else f"are {clearance:.2f} mm apart"
        reasons.append(f"neighbouring beams {word}; the minimum clearance is {rules.min_clearance_mm:g} mm")
    if part.raw_profile is not None:
        short = [e.Length() for e in part.raw_profile.Edges() if e.Length() < rules.min_feature_mm]
        if short:
            reasons.append(f"degenerate feature: {len(short)} profile edge(s) shorter than {rules.min_feature_mm:g} mm "
                           f"(shortest {min(short):.3f} mm)")
    if part.errors:
        return reasons

    solids = part.solid.Solids()
    if len(solids) != 1:
        reasons.append(f"the part is {len(solids)} separate solids, not one")
    elif not part.solid.isValid():
        reasons.append("the B-rep is not a valid closed solid (OCC check failed)")

    gaps = _gaps(part) if clearance >= rules.min_clearance_mm else []
    half = rules.min_feature_mm / 2
    for gap in gaps:
        opened = gap.buffer(-half).buffer(half)
        lost = gap.area - opened.area
        if lost > 0.02 * gap.area:
            reasons.append(f"sliver: {lost:.2f} mm^2 of a gap between beams is narrower than "
                           f"{rules.min_feature_mm:g} mm and would fuse when printed")
            break

    t = params.thickness_mm
    for side, pattern in (("hub", params.hub_bolts), ("ring", params.ring_bolts)):
        radius = max(pattern.hole_diameter_mm, pattern.counterbore_diameter_mm) / 2
        for k, hole in enumerate(pattern.holes()):
            rc = math.hypot(hole.x_mm, hole.y_mm)
            # the bore wall is z-aware: a counterbore only meets the bore over its own depth
            to_bore = rc - pattern.hole_diameter_mm / 2 - params.bore_radius_between(0.0, t)
            if pattern.counterbore_diameter_mm > 0:
                cb_bore = params.bore_radius_between(t - pattern.counterbore_depth_mm, t)
                to_bore = min(to_bore, rc - pattern.counterbore_diameter_mm / 2 - cb_bore)
            walls = {
                "cuts into a gap between beams": min((g.distance(Point(hole.x_mm, hole.y_mm)) - radius
                                                      for g in gaps), default=math.inf),
                "breaks through the outer edge": params.ring_outer_radius_mm - rc - radius,
                "breaks into the central bore": to_bore,
            }
            what, wall = min(walls.items(), key=lambda kv: kv[1])
            if wall < rules.min_wall_mm:
                reasons.append(f"{side} bolt hole {k + 1} {what} (wall {wall:.2f} mm < {rules.min_wall_mm:g} mm)")
                break
    return reasons
