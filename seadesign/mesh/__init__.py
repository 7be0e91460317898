"""Tetrahedral meshes of the compliant element with named boundary facets.

Entry point: mesh_part(). Inputs in mm (part coordinates: axis +z, z in [0, thickness]).
"""

from __future__ import annotations

import hashlib
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from seadesign.errors import MeshError
from seadesign.mesh.extrude import layer_count
from seadesign.mesh.surface import load_stl, tessellate_solid
from seadesign.mesh.tetmesh import MeshQuality, TetMesh, build_tetmesh
from seadesign.design.interfaces import Interfaces
from seadesign.run.cache import default_cache
from seadesign.run.fingerprint import code_fingerprint

__all__ = ["BACKENDS", "MeshQuality", "TetMesh", "load_stl", "mesh_part"]

BACKENDS = ("gmsh", "pytetwild")
MESH_STAGE = "tetmesh"  # the stage cache's folder of raw meshes (points_mm, tets)
REGULAR_TET_VOLUME = 1.0 / (6.0 * np.sqrt(2.0))  # volume of a regular tetrahedron of unit edge


def _surface_volume(v: np.ndarray, f: np.ndarray) -> float:
    t = v[f]
    return float(abs(np.einsum("ij,ij->i", t[:, 0], np.cross(t[:, 1], t[:, 2])).sum()) / 6.0)


def _run_worker(job: dict, inputs: dict[str, bytes], timeout_s: float) -> tuple[np.ndarray, np.ndarray]:
    with tempfile.TemporaryDirectory(prefix="seadesign-mesh-") as d:
        d = Path(d)
        (d / "job.json").write_text(json.dumps(job))
        for name, data in inputs.items():
            (d / name).write_bytes(data)
        try:
            proc = subprocess.run(
                [sys.executable, "-m", "seadesign.mesh.worker", str(d)],
                capture_output=True, text=True, timeout=timeout_s,
            )
        except subprocess.TimeoutExpired:
            raise TimeoutError(f"no mesh within {timeout_s:g} s") from None
        if proc.returncode != 0 or not (d / "tets.npz").is_file():
            tail = "\n".join((proc.stderr or proc.stdout).strip().splitlines()[-3:])
            raise RuntimeError(f"mesher exited with {proc.returncode}: {tail}")
        with np.load(d / "tets.npz") as out:
            return out["points"], out["tets"]


def mesh_part(
    solid_or_surface,
    interfaces: Interfaces,
    elements_across_beam: float,
    beam_width_mm: float,
    cache_dir: str | Path | None = None,
    backend: str = "gmsh",
    elements_per_circle: float = 0.0,
    sweep: bool = True,
    layers: int = 0,
    timeout_s: float = 120.0,
    max_tets: int = 400_000,
    retries: int = 2,
    epsilon: float = 1e-3,
) -> TetMesh:
    """Tetrahedralize a part and name its interface surfaces.

    solid_or_surface: a CadQuery solid (mm), or (vertices_mm (n, 3), faces (k, 3)) of a closed
    surface such as load_stl() returns. Target edge length h = beam_width_mm / elements_across_beam
    (mm). backend "gmsh" (deterministic, CAD solids only; elements_per_circle > 0 refines curved
    surfaces such as bolt holes and fillets to that many elements per full turn; a prismatic
    solid is meshed as its triangulated cross-section swept through the thickness in layers of
    about h graded toward the faces (or `layers` of them when > 0), unless sweep=False) or
    "pytetwild" (any closed surface, uniform size; its edge length and envelope are relative to
    the bounding-box diagonal: edge_length_fac = h / diag, epsilon as given). Each attempt runs
    in a child process limited to timeout_s; a failed, timed-out or oversized (> max_tets) attempt is retried `retries` times, then MeshError.
    Meshes are cached by content in the stage cache rooted at cache_dir (default: `run.cache.default_cache`).
    Its length is the options and this text; the body is five steps (inputs, size check, cache,
    mesh, name the boundaries), each a call.
    """
    _check_options(backend, elements_across_beam, beam_width_mm, layers, elements_per_circle)
    size_mm = beam_width_mm / elements_across_beam
    t0 = time.perf_counter()
    if backend == "gmsh":
        settings, inputs, payload, volume, tag_tol_mm = _gmsh_inputs(solid_or_surface, size_mm, elements_per_circle,
                                                                     sweep, layers)
    else:
        settings, inputs, payload, volume, tag_tol_mm = _pytetwild_inputs(solid_or_surface, size_mm, epsilon)
    t_geom = time.perf_counter() - t0

    estimate = volume / (REGULAR_TET_VOLUME * size_mm**3)
    if estimate > max_tets:
        raise MeshError(
            f"elements_across_beam={elements_across_beam:g} gives about {estimate:,.0f} tetrahedra, more than "
            f"max_tets={max_tets:,}; use fewer elements across the beam or raise max_tets"
        )
    cache = default_cache(cache_dir)
    key = tetmesh_key(settings, payload)
    hit = cache.get(MESH_STAGE, key)
    attempts: list[str] = []
    t1 = time.perf_counter()
    if hit is not None:
        points, tets = hit
    else:
        points, tets, attempts = _mesh_with_retries(settings, inputs, timeout_s, max_tets, retries, size_mm)
        cache.put(MESH_STAGE, key, (points, tets))
    info = {
        **settings,
        "elements_across_beam": elements_across_beam,
        "beam_width_mm": beam_width_mm,
        "target_edge_mm": size_mm,
        "cache_key": key,
        "cache_hit": hit is not None,
        "failed_attempts": attempts,
        "geometry_s": t_geom,
        "tetrahedralize_s": time.perf_counter() - t1,
    }
    return build_tetmesh(points, tets, interfaces, tag_tol_mm, info)


def tetmesh_key(settings: dict, payload: bytes) -> str:
    """sha256 of the meshing settings, the geometry bytes (tessellation or BREP) and the mesher's code."""
    h = hashlib.sha256()
    h.update(json.dumps({"code": code_fingerprint("seadesign.mesh.worker"), **settings}, sort_keys=True).encode())
    h.update(payload)
    return h.hexdigest()


def _check_options(backend: str, elements_across_beam: float, beam_width_mm: float, layers: int,
                   elements_per_circle: float) -> None:
    if backend not in BACKENDS:
        raise MeshError(f"mesh backend {backend!r} is unknown; use one of {', '.join(BACKENDS)}")
    if not (elements_across_beam > 0 and beam_width_mm > 0):
        raise MeshError(
            f"elements_across_beam ({elements_across_beam}) and beam_width_mm ({beam_width_mm}) must be positive"
        )
    if layers < 0:
        raise MeshError(f"layers={layers}: give a positive number of layers, or 0 to derive it from the size")
    if elements_per_circle < 0 or (elements_per_circle > 0 and backend != "gmsh"):
        raise MeshError(f"elements_per_circle={elements_per_circle:g}: curvature-based sizing needs backend 'gmsh' "
                        "and a value >= 0; use 0 for a uniform mesh")


def _gmsh_inputs(solid, size_mm: float, per_circle: float, sweep: bool, layers: int):
    """(settings, worker inputs, cache payload, volume mm^3, tagging tolerance mm) for gmsh."""
    if not hasattr(solid, "exportBrep"):
        raise MeshError("the gmsh backend needs a CAD solid; mesh surfaces (STL) with backend='pytetwild'")
    volume = float(solid.Volume())
    settings = {"backend": "gmsh", "size_mm": size_mm, "per_circle": per_circle}
    section = prismatic_section(solid) if sweep else None
    if section is not None:
        face, z0, thickness = section
        settings["swept"] = {"z0_mm": z0, "thickness_mm": thickness, "layers": layers or layer_count(thickness, size_mm)}
    with tempfile.TemporaryDirectory() as d:
        (face if section is not None else solid).exportBrep(str(Path(d) / "part.brep"))
        payload = (Path(d) / "part.brep").read_bytes()
    return settings, {"part.brep": payload}, payload, volume, 1e-3 * size_mm


def _pytetwild_inputs(solid_or_surface, size_mm: float, epsilon: float):
    """(settings, worker inputs, cache payload, volume mm^3, tagging tolerance mm) for pytetwild."""
    if hasattr(solid_or_surface, "exportBrep"):
        v, f = tessellate_solid(solid_or_surface, tolerance_mm=min(0.01, size_mm / 50))
    else:
        v, f = (np.asarray(a) for a in solid_or_surface)
    diag = float(np.linalg.norm(np.ptp(v, axis=0)))
    settings = {"backend": "pytetwild", "edge_length_fac": size_mm / diag, "epsilon": epsilon}
    payload = np.ascontiguousarray(v, dtype=np.float64).tobytes() + np.ascontiguousarray(f, dtype=np.int64).tobytes()
    return settings, {"surface.npz": _npz_bytes(vertices=v, faces=f)}, payload, _surface_volume(v, f), 2.0 * epsilon * diag


def _mesh_with_retries(settings: dict, inputs: dict[str, bytes], timeout_s: float, max_tets: int, retries: int,
                       size_mm: float) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """Run the mesher in a child process; a failed, timed-out or oversized attempt is retried."""
    attempts: list[str] = []
    for attempt in range(retries + 1):
        try:
            points, tets = _run_worker({**settings, "attempt": attempt}, inputs, timeout_s)
        except (TimeoutError, RuntimeError) as exc:
            attempts.append(str(exc))
            continue
        if len(tets) > max_tets:
            attempts.append(f"{len(tets):,} tetrahedra > max_tets={max_tets:,}")
            continue
        return points, tets, attempts
    raise MeshError(
        f"{settings['backend']} failed {len(attempts)} times at {size_mm:.3g} mm ({'; '.join(attempts)}); "
        "try fewer elements_across_beam, a longer timeout_s or the other backend"
    )


def prismatic_section(solid, rel_tol: float = 1e-6):
    """(bottom face, z0_mm, thickness_mm) when the solid is a straight extrusion along z of its one
    planar bottom face (volume = face area x height, top face alike), else None."""
    bb = solid.BoundingBox()
    height = bb.zmax - bb.zmin
    volume = float(solid.Volume())

    def planar_at(z: float):
        return [f for f in solid.Faces() if f.geomType() == "PLANE" and abs(f.Center().z - z) < 1e-6 * (1 + height)
                and abs(f.normalAt().z) > 1 - 1e-9]

    bottom, top = planar_at(bb.zmin), planar_at(bb.zmax)
    if len(bottom) != 1 or len(top) != 1 or height <= 0:
        return None
    area = float(bottom[0].Area())
    if abs(area * height - volume) > rel_tol * volume or abs(float(top[0].Area()) - area) > rel_tol * area:
        return None
    return bottom[0], float(bb.zmin), float(height)


def _npz_bytes(**arrays: np.ndarray) -> bytes:
    import io

    buf = io.BytesIO()
    np.savez(buf, **arrays)
    return buf.getvalue()
