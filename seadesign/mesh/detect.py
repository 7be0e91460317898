"""Interfaces of a part given only as a surface (e.g. an STL): bolt holes, bore and radii are
read from axial cross-sections. Part coordinates in mm (axis +z, z in [0, thickness])."""

from __future__ import annotations

import numpy as np

from seadesign.errors import MeshError
from seadesign.design.interfaces import Hole, Interfaces


def _sections(vertices: np.ndarray, faces: np.ndarray, fractions: tuple[float, ...]):
    import trimesh

    mesh = trimesh.Trimesh(vertices, faces, process=False)
    t = float(vertices[:, 2].max())
    out = []
    for frac in fractions:
        sec = mesh.section(plane_origin=[0, 0, frac * t], plane_normal=[0, 0, 1])
        if sec is None:
            continue
        planar, _ = sec.to_2D(to_2D=np.eye(4))
        if planar.polygons_full:
            out.append(list(planar.polygons_full))
    return out


def _circular_holes(sections, max_radius_mm: float) -> list[tuple[float, float, float]]:
    holes = []
    for poly in (p for sec in sections for p in sec):
        for ring in poly.interiors:
            c = np.asarray(ring.coords)[:-1]
            centre = c.mean(axis=0)
            r = np.hypot(*(c - centre).T)
            if r.mean() < max_radius_mm and np.ptp(r) < 0.05 * r.mean():
                holes.append((float(centre[0]), float(centre[1]), float(r.mean())))
    return holes


def _coverage(sections, radii: np.ndarray, n_angles: int = 720) -> np.ndarray:
    """Mean over the sections of the fraction of each circle r = radii covered by material."""
    import shapely

    phi = np.linspace(0, 2 * np.pi, n_angles, endpoint=False)
    x = radii[:, None] * np.cos(phi)
    y = radii[:, None] * np.sin(phi)
    cover = [sum(shapely.contains_xy(p, x, y) for p in sec).mean(axis=1) for sec in sections]
    return np.mean(cover, axis=0)


def detect_interfaces(vertices: np.ndarray, faces: np.ndarray) -> Interfaces:
    """Bore, hub bolt holes (inner bolt circle) and ring bolt holes (outer bolt circle) from
    sections at 10-90 % of the thickness; counterbored holes keep their smallest radius."""
    r_out = float(np.hypot(vertices[:, 0], vertices[:, 1]).max())
    polys = _sections(vertices, faces, (0.1, 0.3, 0.5, 0.7, 0.9))
    if not polys:
        raise MeshError("no cross-section of the surface found; is the part axis +z (see --axis)?")
    found = _circular_holes(polys, 0.3 * r_out)
    clusters: list[list[tuple[float, float, float]]] = []
    for h in found:
        for cl in clusters:
            if np.hypot(cl[0][0] - h[0], cl[0][1] - h[1]) < 0.2:
                cl.append(h)
                break
        else:
            clusters.append([h])
    merged = [(np.mean([h[0] for h in cl]), np.mean([h[1] for h in cl]), min(h[2] for h in cl)) for cl in clusters]
    bore = [h for h in merged if np.hypot(h[0], h[1]) < 0.5]
    bolts = [h for h in merged if np.hypot(h[0], h[1]) >= 0.5]
    circles = sorted({round(float(np.hypot(h[0], h[1])) * 2) / 2 for h in bolts})
    if len(circles) < 2:
        raise MeshError(
            f"found bolt holes on {len(circles)} bolt circle(s) ({circles} mm); need an inner (hub) and an outer "
            "(ring) circle of axial round holes"
        )
    on = lambda c: tuple(  # noqa: E731
        Hole(float(h[0]), float(h[1]), float(h[2])) for h in bolts if abs(round(float(np.hypot(h[0], h[1])) * 2) / 2 - c) < 0.25
    )
    hub_holes, ring_holes = on(circles[0]), on(circles[-1])
    radii = np.arange(0.25, r_out, 0.25)
    cov = _coverage(polys, radii)
    hub_end = circles[0] + max(h.radius_mm for h in hub_holes)
    ring_start = circles[-1] - max(h.radius_mm for h in ring_holes)
    gap = (radii > hub_end) & (radii < ring_start) & (cov < 0.5)
    if not gap.any():
        raise MeshError("no beam region (circle less than half covered) found between the bolt circles")
    return Interfaces(
        hub_holes=hub_holes,
        ring_holes=ring_holes,
        bore_radius_mm=float(bore[0][2]) if bore else 0.0,
        hub_radius_mm=float(radii[gap][0]),
        ring_inner_radius_mm=float(radii[gap][-1]),
        ring_outer_radius_mm=r_out,
        thickness_mm=float(vertices[:, 2].max() - vertices[:, 2].min()),
    )
