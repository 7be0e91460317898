"""Printable files of a part: STL via trimesh (checked on read-back) and STEP via CadQuery.

Both are in millimetres, the part's own frame (axis +z).
"""

from __future__ import annotations

from pathlib import Path

import cadquery as cq
import numpy as np
import trimesh

from seadesign.design.candidate import Candidate
from seadesign.design.geometry import Part
from seadesign.errors import SeadesignError


class ExportError(SeadesignError):
    """An exported file failed its read-back check."""


def tessellate(solid: cq.Shape, tolerance_mm: float = 0.01, angular_tolerance_rad: float = 0.1) -> trimesh.Trimesh:
    """Triangulate a solid into one closed surface with shared vertices and outward normals (mm).

    OCC tessellates face by face, duplicating vertices on shared edges; they are merged here.
    """
    vertices, faces = solid.tessellate(tolerance_mm, angular_tolerance_rad)
    mesh = trimesh.Trimesh(np.array([v.toTuple() for v in vertices]), np.asarray(faces, dtype=np.int64), process=False)
    mesh.merge_vertices(digits_vertex=6)
    mesh.update_faces(mesh.nondegenerate_faces(height=1e-9))
    mesh.remove_unreferenced_vertices()
    trimesh.repair.fix_normals(mesh)
    return mesh


def check_printable(mesh: trimesh.Trimesh, cad_volume_mm3: float, what: str, rel_tol: float = 0.005) -> None:
    """Watertight, consistently wound, outward, and the CAD volume within `rel_tol`."""
    problems = []
    if not mesh.is_watertight:
        problems.append("it is not watertight (open or non-manifold edges)")
    if not mesh.is_winding_consistent:
        problems.append("its triangle winding is inconsistent")
    if mesh.volume <= 0:
        problems.append("its normals point inwards (negative volume)")
    dev = abs(mesh.volume - cad_volume_mm3) / cad_volume_mm3
    if dev > rel_tol:
        problems.append(f"its volume {mesh.volume:.1f} mm^3 differs from the CAD volume {cad_volume_mm3:.1f} mm^3 "
                        f"by {100 * dev:.2f} % (> {100 * rel_tol:g} %); use a smaller --tolerance-mm")
    if problems:
        raise ExportError(f"{what}: " + "; ".join(problems))


def write_stl(solid: cq.Shape, path: str | Path, tolerance_mm: float = 0.01) -> Path:
    """Write a binary STL in mm and check it on read-back."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(".tmp.stl")
    tessellate(solid, tolerance_mm).export(tmp)
    check_printable(trimesh.load(tmp, force="mesh"), solid.Volume(), f"STL {path}")
    tmp.replace(path)
    return path


def export_candidate(candidate: Candidate, part: Part, folder: str | Path, tolerance_mm: float = 0.01) -> list[Path]:
    """STL + STEP of a candidate's built part, named by the candidate (`Candidate.stem`)."""
    folder = Path(folder)
    return [write_stl(part.solid, folder / f"{candidate.stem}.stl", tolerance_mm),
            write_step(part.solid, folder / f"{candidate.stem}.step")]


def write_step(solid: cq.Shape, path: str | Path) -> Path:
    """Write a STEP file (mm)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    cq.exporters.export(cq.Workplane().add(solid), str(path), exportType="STEP")
    return path
