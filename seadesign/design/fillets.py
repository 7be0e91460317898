"""Beam-root fillets: every corner where a beam meets the hub or the ring is rounded by exactly the
requested radius, or the candidate is invalid with the reason (mm throughout).

The edges at a root corner are circular arcs (the hub or ring circle and a side of the beam), so
each fillet is computed in closed form: its centre lies at radius +- rho from both circles'
centres, on the gap's side of each. A corner takes the fillet only when both tangent points fall
inside their edges; otherwise (a narrow notch, e.g. a beam's inner arc of radius 1 mm under a
1 mm fillet) the largest radius that fits is reported. The CAD kernel then rounds the corners and
every fillet it makes is checked against the computed centre: none may be missing or misplaced.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cadquery as cq
import numpy as np

TOL_MM = 1e-6
EDGE_MARGIN_MM = 1e-3  # a tangent point closer than this to an edge's far end does not fit


@dataclass(frozen=True)
class Fillet:
    """One rounded root corner: the corner it replaces, its centre, radius and tangent points (mm)."""

    root: str  # "hub" or "ring"
    corner_xy: tuple[float, float]
    center_xy: tuple[float, float]
    radius_mm: float
    tangent_xy: tuple[tuple[float, float], tuple[float, float]]  # on the root circle, on the beam side


@dataclass(frozen=True)
class _Arc:
    """An edge of the gap at a corner: its circle and direction away from the corner."""

    center: np.ndarray
    radius: float
    start: np.ndarray  # the corner
    end: np.ndarray  # the edge's other end
    direction: np.ndarray  # unit tangent at the corner, pointing along the edge


def _xy(v) -> np.ndarray:
    return np.array([v.x, v.y])


def _arcs_at(wire: cq.Wire, corner: np.ndarray) -> list[_Arc]:
    arcs = []
    for e in wire.Edges():
        ends = [_xy(e.startPoint()), _xy(e.endPoint())]
        for k, p in enumerate(ends):
            if np.linalg.norm(p - corner) < 1e-6:
                if e.geomType() != "CIRCLE":
                    raise ValueError(f"a root corner edge is a {e.geomType().lower()}, not an arc")
                center = _xy(e.arcCenter())
                radial = corner - center
                tangent = np.array([-radial[1], radial[0]]) / np.linalg.norm(radial)
                if np.dot(tangent, _xy(e.positionAt(0.5)) - corner) < 0:  # point along the edge
                    tangent = -tangent
                arcs.append(_Arc(center, e.radius(), corner, ends[1 - k], tangent))
    if len(arcs) != 2:
        raise ValueError(f"expected two edges at the corner {corner.round(3).tolist()}, found {len(arcs)}")
    return arcs


def _on_arc(arc: _Arc, point: np.ndarray) -> bool:
    """Whether `point` (on the arc's circle) lies strictly inside the edge, going from the corner."""
    r, d = arc.start - arc.center, arc.direction
    sense = np.sign(r[0] * d[1] - r[1] * d[0])

    def angle(p):
        d = p - arc.center
        return math.atan2(d[1], d[0])

    to_point = (sense * (angle(point) - angle(arc.start))) % (2 * math.pi)
    to_end = (sense * (angle(arc.end) - angle(arc.start))) % (2 * math.pi) or 2 * math.pi
    return 0 < to_point < to_end - EDGE_MARGIN_MM / arc.radius and to_point < math.pi


def _fillet_at(arcs: list[_Arc], rho: float) -> tuple[np.ndarray, list[np.ndarray]] | None:
    """Centre and tangent points of the fillet of radius rho in the corner, None when it does not fit."""
    corner = arcs[0].start
    inward = arcs[0].direction + arcs[1].direction  # into the gap (root corners of a gap are convex)
    probe = corner + 1e-4 * rho * inward / np.linalg.norm(inward)
    offsets = [a.radius + (rho if np.linalg.norm(probe - a.center) > a.radius else -rho) for a in arcs]
    a, b = arcs[0].center, arcs[1].center
    d = np.linalg.norm(b - a)
    if offsets[0] <= 0 or offsets[1] <= 0 or d < TOL_MM:
        return None
    x = (d**2 + offsets[0] ** 2 - offsets[1] ** 2) / (2 * d)
    h2 = offsets[0] ** 2 - x**2
    if h2 < 0:
        return None
    u = (b - a) / d
    n = np.array([-u[1], u[0]])
    centres = [a + x * u + s * math.sqrt(h2) * n for s in (1, -1)]
    center = min(centres, key=lambda c: np.linalg.norm(c - probe))
    tangents = [arc.center + arc.radius * (center - arc.center) / np.linalg.norm(center - arc.center) for arc in arcs]
    if not all(_on_arc(arc, t) for arc, t in zip(arcs, tangents)):
        return None
    return center, tangents


def _largest_fitting(arcs: list[_Arc], rho: float) -> float:
    lo, hi = 0.0, rho
    for _ in range(40):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if _fillet_at(arcs, mid) is not None else (lo, mid)
    return lo


def fillet_gap(gap: cq.Face, corners: list[tuple[str, np.ndarray]], rho: float) -> tuple[cq.Face, list[Fillet]]:
    """Round the root corners (root name, xy) of one gap face by rho; ValueError names a corner that
    cannot take it (with the largest radius that fits) or a fillet the kernel did not make."""
    wire = gap.outerWire()
    fillets = []
    for root, corner in corners:
        arcs = _arcs_at(wire, corner)
        arcs.sort(key=lambda arc: np.linalg.norm(arc.center) > TOL_MM)  # the root circle (centred on the axis) first
        found = _fillet_at(arcs, rho)
        if found is None:
            raise ValueError(f"the {rho:g} mm root fillet does not fit where a beam side of radius "
                             f"{arcs[1].radius:g} mm meets the {root} at ({corner[0]:.2f}, {corner[1]:.2f}) mm; "
                             f"the largest that fits there is {math.floor(_largest_fitting(arcs, rho) * 1e3) / 1e3:.3f} mm")
        center, tangents = found
        fillets.append(Fillet(root, tuple(corner), tuple(center), rho, tuple(tuple(t) for t in tangents)))
    vertices = [v for v in gap.Vertices() if any(np.linalg.norm(np.array([v.X, v.Y]) - c) < 1e-6 for _, c in corners)]
    rounded = gap.fillet2D(rho, vertices)
    made = [_xy(e.arcCenter()) for e in rounded.Edges() if e.geomType() == "CIRCLE" and abs(e.radius() - rho) < 1e-9]
    for f in fillets:
        if not any(np.linalg.norm(c - np.array(f.center_xy)) < 1e-5 for c in made):
            raise ValueError(f"the CAD kernel did not make the {rho:g} mm fillet at the {f.root} corner "
                             f"({f.corner_xy[0]:.2f}, {f.corner_xy[1]:.2f}) mm")
    return rounded, fillets
