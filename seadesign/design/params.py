"""The parameters of a candidate and the printability rules it is checked against (mm, deg),
and the strict reading of a `[geometry]` table into them.

Plain data with no CAD dependency, so studies load and hash without importing the CAD kernel.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from seadesign.design.interfaces import Hole, Interfaces
from seadesign.design.tomlcheck import Table


@dataclass(frozen=True)
class BoltPattern:
    """`count` through holes on a circle, axial; optional counterbore from the top face (z = thickness)."""

    count: int
    circle_diameter_mm: float
    hole_diameter_mm: float
    start_angle_deg: float = 0.0
    counterbore_diameter_mm: float = 0.0  # 0: none
    counterbore_depth_mm: float = 0.0

    def holes(self) -> tuple[Hole, ...]:
        r = self.circle_diameter_mm / 2
        return tuple(
            Hole(r * math.cos(a), r * math.sin(a), self.hole_diameter_mm / 2)
            for a in (math.radians(self.start_angle_deg) + 2 * math.pi * i / self.count for i in range(self.count))
        )


@dataclass(frozen=True)
class NutSlots:
    """Radial slots through the ring at each ring bolt, for captive nuts (mm)."""

    width_mm: float  # tangential width (nut across flats plus clearance)
    z_min_mm: float
    z_max_mm: float


@dataclass(frozen=True)
class GeometryParams:
    """Every dimension of one candidate (mm, deg)."""

    beam_count: int
    beam_thickness_mm: float  # in-plane width of a beam
    hub_radius_mm: float
    arc_radius_mm: float  # centreline radius of each of a beam's two arcs
    ring_width_mm: float  # radial width of the outer ring
    thickness_mm: float  # axial thickness of the part
    first_beam_angle_deg: float
    clockwise: bool  # handedness of the S (as seen from +z, the first arc turns clockwise)
    fillet_radius_mm: float  # at the beam roots; 0 = sharp
    hub_bolts: BoltPattern
    ring_bolts: BoltPattern
    bore_radius_mm: float = 0.0  # plain central bore; see bore_profile_mm
    bore_profile_mm: tuple[tuple[float, float], ...] = field(default=())  # (z, r) points of a revolved bore
    nut_slots: NutSlots | None = None

    @property
    def ring_inner_radius_mm(self) -> float:
        return self.hub_radius_mm + 2 * self.arc_radius_mm

    @property
    def ring_outer_radius_mm(self) -> float:
        return self.ring_inner_radius_mm + self.ring_width_mm

    def bore_radius_between(self, z0_mm: float, z1_mm: float) -> float:
        """Largest central-bore radius over z0 <= z <= z1 (mm)."""
        radius = self.bore_radius_mm
        if self.bore_profile_mm:
            zs = [z for z, _ in self.bore_profile_mm]
            rs = [r for _, r in self.bore_profile_mm]
            inside = [r for z, r in self.bore_profile_mm if z0_mm <= z <= z1_mm]
            ends = [float(np.interp(z, zs, rs, left=0.0, right=0.0)) for z in (z0_mm, z1_mm)]
            radius = max([radius] + inside + ends)
        return radius

    def interfaces(self) -> Interfaces:
        bore = self.bore_radius_between(0.0, self.thickness_mm)
        return Interfaces(
            hub_holes=self.hub_bolts.holes(),
            ring_holes=self.ring_bolts.holes(),
            bore_radius_mm=bore,
            hub_radius_mm=self.hub_radius_mm,
            ring_inner_radius_mm=self.ring_inner_radius_mm,
            ring_outer_radius_mm=self.ring_outer_radius_mm,
            thickness_mm=self.thickness_mm,
        )


@dataclass(frozen=True)
class ValidityRules:
    """Printability limits (mm)."""

    min_clearance_mm: float  # gap between neighbouring beams
    min_feature_mm: float  # shortest edge / narrowest slit the printer resolves
    min_wall_mm: float  # material between a bolt hole and a gap or outer edge


def _bolts(g: Table, name: str) -> BoltPattern:
    b = g.table(name)
    pattern = BoltPattern(
        count=b.integer("count", ge=1),
        circle_diameter_mm=b.number("circle_diameter_mm", gt=0),
        hole_diameter_mm=b.number("hole_diameter_mm", gt=0),
        start_angle_deg=b.number("start_angle_deg", 0.0),
        counterbore_diameter_mm=b.number("counterbore_diameter_mm", 0.0, ge=0),
        counterbore_depth_mm=b.number("counterbore_depth_mm", 0.0, ge=0),
    )
    b.done()
    if pattern.counterbore_diameter_mm and pattern.counterbore_diameter_mm <= pattern.hole_diameter_mm:
        raise b.error(b.key("counterbore_diameter_mm"), "must be larger than hole_diameter_mm")
    return pattern


def _bore_profile(g: Table) -> tuple[tuple[float, float], ...]:
    profile = g.raw("bore_profile_mm", [])
    if not isinstance(profile, list) or any(
        not isinstance(p, list) or len(p) != 2 or not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in p)
        for p in profile
    ):
        raise g.error(g.key("bore_profile_mm"), "must be a list of [z_mm, radius_mm] pairs")
    return tuple((float(z), float(r)) for z, r in profile)


def read_geometry(g: Table) -> GeometryParams:
    """Every key of a `[geometry]` table (design-axis values merged in), checked for type, range
    and impossible combinations; errors name the key where the value came from."""
    slots = g.table("nut_slots", optional=True)
    p = GeometryParams(
        beam_count=g.integer("beam_count", gt=0),
        beam_thickness_mm=g.number("beam_thickness_mm", gt=0),
        hub_radius_mm=g.number("hub_radius_mm", gt=0),
        arc_radius_mm=g.number("arc_radius_mm", gt=0),
        ring_width_mm=g.number("ring_width_mm", gt=0),
        thickness_mm=g.number("thickness_mm", gt=0),
        first_beam_angle_deg=g.number("first_beam_angle_deg"),
        clockwise=g.boolean("clockwise"),
        fillet_radius_mm=g.number("fillet_radius_mm", ge=0),
        bore_radius_mm=g.number("bore_radius_mm", 0.0, ge=0),
        hub_bolts=_bolts(g, "hub_bolts"),
        ring_bolts=_bolts(g, "ring_bolts"),
        bore_profile_mm=_bore_profile(g),
        nut_slots=None if slots is None else NutSlots(slots.number("width_mm", gt=0), slots.number("z_min_mm", ge=0),
                                                       slots.number("z_max_mm", gt=0)),
    )
    if slots is not None:
        slots.done()
    g.done()
    _check_combinations(g, p)
    return p


def _unindexed(key: str) -> str:
    """A key without its list index ("design_space.x[1]" -> "design_space.x"), where the value is printed."""
    return key.split("[", 1)[0]


def _check_combinations(g: Table, p: GeometryParams) -> None:
    """Impossible combinations of valid values, named by key."""
    if p.beam_thickness_mm / 2 >= p.arc_radius_mm:
        raise g.error(_unindexed(g.key("beam_thickness_mm")), f"value {p.beam_thickness_mm:g} mm needs "
                      f"{_unindexed(g.key('arc_radius_mm'))} > {p.beam_thickness_mm / 2:g} mm (half the beam width)")
    bore = max([p.bore_radius_mm] + [r for _, r in p.bore_profile_mm])
    if bore >= p.hub_radius_mm:
        raise g.error(g.key("bore_radius_mm"), f"({bore:g} mm) must be smaller than hub_radius_mm ({p.hub_radius_mm:g} mm)")
    for name, lo, hi in (("hub_bolts", bore, p.hub_radius_mm), ("ring_bolts", p.ring_inner_radius_mm,
                                                                 p.ring_outer_radius_mm)):
        pat: BoltPattern = getattr(p, name)
        r = pat.circle_diameter_mm / 2
        if not lo < r - pat.hole_diameter_mm / 2 or not r + pat.hole_diameter_mm / 2 < hi:
            raise g.error(g.key(f"{name}.circle_diameter_mm"),
                          f"puts the holes (radius {r:g} mm +- {pat.hole_diameter_mm / 2:g}) outside the "
                          f"{'hub' if name == 'hub_bolts' else 'ring'} ({lo:g} to {hi:g} mm)")
    for z, r in p.bore_profile_mm:
        if not 0 <= z <= p.thickness_mm or not 0 < r:
            raise g.error(g.key("bore_profile_mm"), f"point [{z:g}, {r:g}] lies outside 0 <= z <= thickness_mm, r > 0")
    s = p.nut_slots
    if s is not None and not s.z_min_mm < s.z_max_mm <= p.thickness_mm:
        raise g.error(g.key("nut_slots"), "needs z_min_mm < z_max_mm <= thickness_mm")
