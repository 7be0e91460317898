"""The parameters of a candidate and the printability rules it is checked against (mm, deg).

Plain data with no CAD dependency, so studies load and hash without importing the CAD kernel.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from seadesign.design.interfaces import Hole, Interfaces


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
