"""Where a compliant element is bolted: the seam between geometry and FEA.

Part coordinates are millimetres, the spring axis is +z through the origin, and the part
spans z in [0, thickness_mm].
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Hole:
    """A through hole parallel to the axis: centre (x_mm, y_mm) and radius_mm."""

    x_mm: float
    y_mm: float
    radius_mm: float


@dataclass(frozen=True)
class Interfaces:
    """The bolted interfaces of a compliant element.

    hub: horn side (motor attachment), ring: backplate side (link). A load case couples the
    walls of one side's holes rigidly (RBE2-like) and applies torque or holds them.
    """

    hub_holes: tuple[Hole, ...]
    ring_holes: tuple[Hole, ...]
    bore_radius_mm: float  # central bore of the hub, 0 when there is none
    hub_radius_mm: float  # outer radius of the hub ("bearing radius")
    ring_inner_radius_mm: float
    ring_outer_radius_mm: float
    thickness_mm: float  # axial thickness
