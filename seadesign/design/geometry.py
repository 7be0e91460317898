"""The compliant element as a CadQuery solid, built from named parameters (all lengths mm).

Shape (the family of the Hamburg Bit-Bots' published spring, `sea_ninjaflex.stl`, MIT, as measured from that
file): a hub (radius `hub_radius_mm`) and an outer ring joined
by N equally spaced beams of one handedness. Each beam is an "S" of two opposed circular arcs
of centreline radius `arc_radius_mm` and constant width `beam_thickness_mm`: the first arc is
centred on the hub circle, the second on the ring's inner circle, and they are tangent half
way, so the ring's inner radius is hub_radius + 2 arc_radius. Beams are clipped to the gap
between hub and ring. Fillets of exactly `fillet_radius_mm` round every beam-root corner (or the
part is not built, with the reason: fillets.py); bolt holes (with optional counterbores), a
central bore and optional radial nut slots are cut afterwards.

Part frame: axis +z through the origin, the part spans z in [0, thickness_mm], the first
beam's arc centres lie on the ray at `first_beam_angle_deg` from +x.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cadquery as cq
import numpy as np

from seadesign.design.fillets import Fillet, fillet_gap
from seadesign.design.params import GeometryParams
from seadesign.design.interfaces import Interfaces


@dataclass
class Part:
    """A built candidate: the solid plus the pieces the validity checks look at."""

    params: GeometryParams
    solid: cq.Solid | None  # None when the construction itself failed
    beams: list[cq.Face]  # each beam's clipped 2D region (z = 0)
    profile: cq.Shape | None  # 2D profile before holes, after fillets (a Face when beams join hub and ring)
    raw_profile: cq.Shape | None  # 2D profile before fillets
    errors: list[str]  # construction failures (each is an invalidity reason)
    fillets: tuple[Fillet, ...] = ()  # the rounded root corners, one per corner

    @property
    def interfaces(self) -> Interfaces:
        return self.params.interfaces()

    @property
    def volume_mm3(self) -> float:
        return self.solid.Volume() if self.solid is not None else float("nan")


def _disk(r: float, center: tuple[float, float] = (0.0, 0.0)) -> cq.Face:
    return cq.Face.makeFromWires(cq.Wire.makeCircle(r, cq.Vector(*center, 0), cq.Vector(0, 0, 1)))


def _annulus(r_in: float, r_out: float, center: tuple[float, float] = (0.0, 0.0)) -> cq.Face:
    c = cq.Vector(*center, 0)
    n = cq.Vector(0, 0, 1)
    return cq.Face.makeFromWires(cq.Wire.makeCircle(r_out, c, n), [cq.Wire.makeCircle(r_in, c, n)])


def _half_plane(upper: bool, size: float) -> cq.Face:
    y0, y1 = (0.0, size) if upper else (-size, 0.0)
    pts = [cq.Vector(-size, y0, 0), cq.Vector(size, y0, 0), cq.Vector(size, y1, 0), cq.Vector(-size, y1, 0)]
    return cq.Face.makeFromWires(cq.Wire.makePolygon(pts, close=True))


def _only_face(shape: cq.Shape) -> cq.Face:
    faces = shape.Faces()
    if len(faces) != 1:
        raise ValueError(f"expected one face, got {len(faces)}")
    return faces[0]


def beam_face(p: GeometryParams, index: int) -> cq.Face:
    """The 2D region of beam `index` (z = 0), clipped to the gap between hub and ring."""
    r_h, r_arc, half_w = p.hub_radius_mm, p.arc_radius_mm, p.beam_thickness_mm / 2
    big = 4 * p.ring_outer_radius_mm
    first_up = not p.clockwise
    arc1 = _annulus(r_arc - half_w, r_arc + half_w, (r_h, 0.0)).intersect(_half_plane(first_up, big))
    arc2 = _annulus(r_arc - half_w, r_arc + half_w, (r_h + 2 * r_arc, 0.0)).intersect(_half_plane(not first_up, big))
    # Reach a little into hub and ring so that the union overlaps instead of touching.
    overlap = min(0.5, 0.25 * p.ring_width_mm, 0.25 * r_h)
    clip = _annulus(r_h - overlap, p.ring_inner_radius_mm + overlap)
    beam = _only_face(arc1.fuse(arc2).clean().intersect(clip))
    angle = p.first_beam_angle_deg + 360.0 * index / p.beam_count
    return beam.rotate(cq.Vector(0, 0, 0), cq.Vector(0, 0, 1), angle)


def build_profile(p: GeometryParams) -> tuple[list[cq.Face], cq.Shape]:
    """The beams and the unfilleted profile (z = 0, no holes): one face, or with no beams
    the hub and ring as two faces."""
    beams = [beam_face(p, i) for i in range(p.beam_count)]
    shape = _annulus(p.ring_inner_radius_mm, p.ring_outer_radius_mm).fuse(_disk(p.hub_radius_mm), *beams).clean()
    return beams, (_only_face(shape) if beams else shape)


def root_corners(p: GeometryParams, gap: cq.Face) -> list[tuple[str, np.ndarray]]:
    """The corners of a gap where a beam meets the hub or the ring: (which, xy in mm)."""
    out = []
    for v in gap.Vertices():
        r = math.hypot(v.X, v.Y)
        for name, radius in (("hub", p.hub_radius_mm), ("ring", p.ring_inner_radius_mm)):
            if abs(r - radius) < 1e-3:
                out.append((name, np.array([v.X, v.Y])))
    return out


def fillet_roots(p: GeometryParams, raw: cq.Face) -> tuple[cq.Face, tuple[Fillet, ...]]:
    """Round every corner where a beam meets the hub or the ring by `fillet_radius_mm`, exactly
    (see fillets.py; ValueError names a corner that cannot take it).

    Each gap between beams is filleted as its own simple face (its root corners are convex
    there), then the profile is rebuilt from the outer wire and the rounded gaps.
    """
    if p.fillet_radius_mm <= 0 or p.beam_count == 0:
        return raw, ()
    gaps, made = [], []
    for wire in raw.innerWires():
        gap = cq.Face.makeFromWires(wire)
        rounded, fillets = fillet_gap(gap, root_corners(p, gap), p.fillet_radius_mm)
        gaps.append(rounded.outerWire())
        made += fillets
    profile = cq.Face.makeFromWires(raw.outerWire(), gaps)
    if not profile.isValid():
        raise ValueError("the filleted profile is not a valid face")
    return profile, tuple(made)


def _cutters(p: GeometryParams) -> list[cq.Solid]:
    """Solids removed from the extruded profile: bolt holes, counterbores, bore, nut slots."""
    t = p.thickness_mm
    cut: list[cq.Solid] = []
    for pattern in (p.hub_bolts, p.ring_bolts):
        for h in pattern.holes():
            cut.append(cq.Solid.makeCylinder(h.radius_mm, t + 2, cq.Vector(h.x_mm, h.y_mm, -1)))
            if pattern.counterbore_diameter_mm > 0:
                depth = pattern.counterbore_depth_mm
                base = cq.Vector(h.x_mm, h.y_mm, t - depth)
                cut.append(cq.Solid.makeCylinder(pattern.counterbore_diameter_mm / 2, depth + 1, base))
    if p.bore_radius_mm > 0:
        cut.append(cq.Solid.makeCylinder(p.bore_radius_mm, t + 2, cq.Vector(0, 0, -1)))
    if p.bore_profile_mm:
        pts = [(0.0, z) for z, _ in (p.bore_profile_mm[0],)] + [(r, z) for z, r in p.bore_profile_mm]
        pts.append((0.0, p.bore_profile_mm[-1][0]))
        wire = cq.Wire.makePolygon([cq.Vector(x, 0, z) for x, z in pts], close=True)
        cut.append(cq.Solid.revolve(cq.Face.makeFromWires(wire), 360, cq.Vector(0, 0, 0), cq.Vector(0, 0, 1)))
    if p.nut_slots is not None:
        s = p.nut_slots
        length = p.ring_width_mm + 2.0
        for h in p.ring_bolts.holes():
            angle = math.degrees(math.atan2(h.y_mm, h.x_mm))
            box = cq.Solid.makeBox(length, s.width_mm, s.z_max_mm - s.z_min_mm,
                                   cq.Vector(p.ring_inner_radius_mm - 1.0, -s.width_mm / 2, s.z_min_mm))
            cut.append(box.rotate(cq.Vector(0, 0, 0), cq.Vector(0, 0, 1), angle))
    return cut


def build_part(p: GeometryParams) -> Part:
    """Build the candidate's solid. Construction failures are recorded as reasons, not raised."""
    # OCC failures surface as assorted exception types, hence the broad excepts.
    try:
        beams, raw = build_profile(p)
    except Exception as exc:
        return Part(p, None, [], None, None, [f"the beams and rings do not fuse into one profile ({exc})"])
    try:
        profile, fillets = fillet_roots(p, raw)
    except Exception as exc:
        return Part(p, None, beams, None, raw, [f"beam-root fillets cannot be made: {exc}"])
    try:
        pieces = [cq.Solid.extrudeLinear(f, cq.Vector(0, 0, p.thickness_mm)) for f in profile.Faces()]
        solid = pieces[0] if len(pieces) == 1 else cq.Compound.makeCompound(pieces)
        cutters = _cutters(p)
        if cutters:
            solid = solid.cut(*cutters).clean()
    except Exception as exc:
        return Part(p, None, beams, profile, raw, [f"cutting holes, bore or slots failed ({exc})"], fillets)
    solids = solid.Solids()
    return Part(p, solids[0] if len(solids) == 1 else solid, beams, profile, raw, [], fillets)
