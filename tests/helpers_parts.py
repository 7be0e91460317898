"""Small CadQuery parts with known interfaces for mesh and solver tests."""

from __future__ import annotations

import cadquery as cq
import numpy as np

from seadesign.design.interfaces import Hole, Interfaces


def holed_annulus() -> tuple[cq.Solid, Interfaces]:
    """Flat annulus (bore 3, outer 20, 5 thick, mm) with 4 hub holes (r 1.2 on a 6 mm circle)
    and 6 ring holes (r 1.5 on a 17 mm circle)."""
    hub = tuple(Hole(6.0 * np.cos(a), 6.0 * np.sin(a), 1.2) for a in np.arange(4) * np.pi / 2)
    ring = tuple(Hole(17.0 * np.cos(a), 17.0 * np.sin(a), 1.5) for a in np.arange(6) * np.pi / 3)
    wp = cq.Workplane("XY").circle(20.0).circle(3.0).extrude(5.0)
    for h in hub + ring:
        wp = wp.cut(cq.Workplane("XY").center(h.x_mm, h.y_mm).circle(h.radius_mm).extrude(5.0))
    ifc = Interfaces(hub, ring, bore_radius_mm=3.0, hub_radius_mm=9.0, ring_inner_radius_mm=14.0,
                     ring_outer_radius_mm=20.0, thickness_mm=5.0)
    return wp.val(), ifc
