"""The per-candidate stages of a sweep: geometry -> validity -> mesh -> unit FEA -> load cases.

Each expensive stage is cached under a key made of its inputs and the previous stage's key,
so changing one input recomputes only the stages that depend on it. The FEA is solved once
for 1 Nm of hub torque (ring held); both load cases are that response scaled, since the
model is linear (see seadesign/fea/torsion.py).

Meshing wraps the mesh package's public pieces (surface tessellation, pytetwild,
`build_tetmesh`) until it offers a single solid -> mesh entry point.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Callable

import numpy as np

from seadesign.cache import Cache, digest, package_versions
from seadesign.errors import MeshError
from seadesign.geometry import GeometryParams
from seadesign.study import Study

Progress = Callable[[str], None]  # receives the name of the stage that starts


@dataclass(frozen=True)
class SolverSettings:
    """Numerical settings that change results (part of every FEA cache key)."""

    element_order: int = 2  # P2 tetrahedra; P1 is solved as well for the error estimate
    linear_solver: str = "pardiso"  # "pardiso" or "scipy"
    tessellation_tol_mm: float = 0.05  # chordal tolerance of the surface handed to the mesher
    boundary_tol_mm: float = 0.1  # distance within which a facet belongs to an interface cylinder
    mesh_optimization_iterations: int = 20  # pytetwild optimisation passes (quality vs time)


@dataclass(frozen=True)
class Geometry:
    """Validity verdict and volume of one candidate."""

    reasons: tuple[str, ...]
    volume_mm3: float

    @property
    def valid(self) -> bool:
        return not self.reasons


@dataclass(frozen=True)
class UnitResponse:
    """FEA response per 1 Nm of torque (SI: m, N, Pa, rad per Nm) plus vertex fields for renders."""

    k_Nm_per_rad: float  # P2 stiffness
    k_p1_Nm_per_rad: float  # P1 stiffness on the same mesh (error estimate)
    n_dofs: int
    hub_max_displacement_m: float  # largest nodal displacement of the coupled hub surface
    hub_bolt_reaction_N: float  # largest single hub-bolt reaction force
    ring_bolt_reaction_N: float  # largest single ring-bolt reaction force
    von_mises_Pa: float  # peaks of the nodal (L2-projected) stresses
    principal_1_Pa: float
    principal_3_Pa: float  # most negative third principal stress (compression, < 0)
    max_shear_Pa: float
    points_mm: np.ndarray  # (n, 3) mesh vertices
    tets: np.ndarray  # (m, 4)
    vertex_displacement_m: np.ndarray  # (n, 3) per Nm
    vertex_von_mises_Pa: np.ndarray  # (n,) per Nm
    mesh_quality: dict  # MeshQuality.as_dict() of the mesh it was solved on
    timings_s: dict


def geometry_key(study: Study, params: GeometryParams) -> str:
    return digest("geometry", params, study.validity, package_versions(("seadesign", "cadquery")))


def mesh_key(study: Study, params: GeometryParams, settings: SolverSettings) -> str:
    return digest("mesh", geometry_key(study, params), study.mesh, settings.tessellation_tol_mm,
                  settings.boundary_tol_mm, settings.mesh_optimization_iterations, package_versions(("pytetwild",)))


def fea_key(study: Study, params: GeometryParams, settings: SolverSettings) -> str:
    m = study.material
    return digest("fea", mesh_key(study, params, settings), m.youngs_modulus_Pa, m.poisson_ratio,
                  settings.element_order, settings.linear_solver, package_versions())


def check_geometry(study: Study, params: GeometryParams, cache: Cache) -> tuple[Geometry, object | None]:
    """Geometry verdict (cached) and the built CheckedPart when it had to be built (else None)."""
    key = geometry_key(study, params)
    hit = cache.get("geometry", key)
    if hit is not None:
        return hit, None
    from seadesign.candidates import check_candidate

    checked = check_candidate(study, params)
    geo = Geometry(tuple(checked.reasons), float(checked.part.volume_mm3))
    cache.put("geometry", key, geo)
    return geo, checked


def tetrahedralize(study: Study, params: GeometryParams, checked, settings: SolverSettings):
    """Tetrahedral mesh (mm) of a checked part with named interface boundaries."""
    import pytetwild

    from seadesign.mesh.surface import tessellate_solid
    from seadesign.mesh.tetmesh import build_tetmesh

    if study.mesh.backend != "pytetwild":
        raise MeshError(f"mesh.backend '{study.mesh.backend}' is not available to the sweep; set it to 'pytetwild'")
    edge_mm = params.beam_thickness_mm / study.mesh.elements_across_beam
    v, f = tessellate_solid(checked.part.solid, settings.tessellation_tol_mm)
    t0 = time.perf_counter()
    pts, tets = pytetwild.tetrahedralize(v, f.astype(np.int32), edge_length_abs=edge_mm, num_threads=1,
                                         num_opt_iter=settings.mesh_optimization_iterations)
    info = {"backend": "pytetwild", "edge_length_mm": edge_mm, "seconds": time.perf_counter() - t0}
    return build_tetmesh(pts, tets, checked.part.interfaces, settings.boundary_tol_mm, info)


def _bolt_reaction(force_N: np.ndarray, groups: dict[str, np.ndarray]) -> float:
    """Largest resultant force (N) over the bolt-hole node groups."""
    return max(float(np.linalg.norm(force_N[nodes].sum(axis=0))) for nodes in groups.values())


def unit_response(mesh, study: Study, settings: SolverSettings) -> UnitResponse:
    """Solve 1 Nm on the hub (P2, and P1 for the error estimate) and reduce it to peaks and fields."""
    from seadesign.fea.stress import invariants, project_to_nodes, vertex_stresses
    from seadesign.fea.torsion import solve_unit_torsion, surface_nodes

    m = study.material
    t0 = time.perf_counter()
    sol = solve_unit_torsion(mesh, m.youngs_modulus_Pa, m.poisson_ratio, order=settings.element_order,
                             linear_solver=settings.linear_solver)
    t1 = time.perf_counter()
    p1 = solve_unit_torsion(mesh, m.youngs_modulus_Pa, m.poisson_ratio, order=1, linear_solver=settings.linear_solver)
    t2 = time.perf_counter()
    stress = project_to_nodes(sol.emesh, vertex_stresses(sol.emesh, sol.displacement_m, m.youngs_modulus_Pa,
                                                         m.poisson_ratio))
    inv = invariants(stress)
    t3 = time.perf_counter()
    hub_nodes = np.unique(np.concatenate(list(sol.hub_groups.values())))
    ring_groups = {n: surface_nodes(sol.emesh, mesh.boundary_faces[mesh.boundaries[n]])
                   for n in mesh.boundaries if n.startswith("ring_hole_")} or {"ring": sol.ring_nodes}
    nv = sol.emesh.n_vertices
    return UnitResponse(
        k_Nm_per_rad=1.0 / float(sol.hub_motion[5]),
        k_p1_Nm_per_rad=1.0 / float(p1.hub_motion[5]),
        n_dofs=sol.n_dofs,
        hub_max_displacement_m=float(np.linalg.norm(sol.displacement_m[hub_nodes], axis=1).max()),
        hub_bolt_reaction_N=_bolt_reaction(sol.nodal_force_N, sol.hub_groups),
        ring_bolt_reaction_N=_bolt_reaction(sol.nodal_force_N, ring_groups),
        von_mises_Pa=float(inv["von_mises"].max()),
        principal_1_Pa=float(inv["principal_1"].max()),
        principal_3_Pa=float(inv["principal_3"].min()),
        max_shear_Pa=float(inv["max_shear"].max()),
        points_mm=mesh.points_mm,
        tets=mesh.tets,
        vertex_displacement_m=sol.displacement_m[:nv],
        vertex_von_mises_Pa=inv["von_mises"][:nv],
        mesh_quality=mesh.quality.as_dict(),
        timings_s={**sol.timings_s, "p1_s": t2 - t1, "stress_s": t3 - t2, "p2_s": t1 - t0},
    )


def load_case_columns(unit: UnitResponse, study: Study) -> dict[str, float]:
    """Both load cases from the unit response (linear scaling), units in the names.

    Stall: the servo's stall torque on the hub, displacement read on the bearing circle (thesis
    eq. 5.3) and mapped to the foot. Impact: the foot-strike torque on the backplate side; the
    reaction is the largest force on one hub bolt (where the motor attaches).
    """
    lc, m = study.load_cases, study.material
    allowable = m.yield_strength_Pa
    out: dict[str, float] = {"k_Nm_per_rad": unit.k_Nm_per_rad, "k_p1_Nm_per_rad": unit.k_p1_Nm_per_rad,
                             "k_rel_error": abs(unit.k_p1_Nm_per_rad - unit.k_Nm_per_rad) / unit.k_Nm_per_rad,
                             "n_dofs": unit.n_dofs}
    for case, torque in (("stall", lc.stall_torque_Nm), ("impact", lc.impact_torque_Nm)):
        rotation = torque / unit.k_Nm_per_rad
        out[f"{case}_torque_Nm"] = torque
        out[f"{case}_rotation_rad"] = rotation
        out[f"{case}_rotation_deg"] = math.degrees(rotation)
        out[f"{case}_bearing_displacement_mm"] = rotation * study.bearing_radius_mm
        out[f"{case}_max_displacement_mm"] = torque * unit.hub_max_displacement_m * 1e3
        out[f"{case}_hub_bolt_reaction_N"] = torque * unit.hub_bolt_reaction_N
        out[f"{case}_ring_bolt_reaction_N"] = torque * unit.ring_bolt_reaction_N
        out[f"{case}_peak_von_mises_MPa"] = torque * unit.von_mises_Pa * 1e-6
        out[f"{case}_peak_principal_1_MPa"] = torque * unit.principal_1_Pa * 1e-6
        out[f"{case}_peak_principal_3_MPa"] = torque * unit.principal_3_Pa * 1e-6
        out[f"{case}_peak_shear_MPa"] = torque * unit.max_shear_Pa * 1e-6
        out[f"{case}_yield_safety_factor"] = allowable / (torque * unit.von_mises_Pa)
    out["stall_foot_error_mm"] = out["stall_bearing_displacement_mm"] / study.bearing_radius_mm * lc.lower_leg_m * 1e3
    return out


def fea_response(study: Study, params: GeometryParams, checked, settings: SolverSettings, cache: Cache,
                 progress: Progress) -> UnitResponse:
    """Unit response via the cache: the mesh (cached) is made only when the solve is not cached."""
    fkey = fea_key(study, params, settings)
    unit = cache.get("fea", fkey)
    if unit is not None:
        return unit
    mkey = mesh_key(study, params, settings)
    mesh = cache.get("mesh", mkey)
    if mesh is None:
        if checked is None:
            from seadesign.candidates import check_candidate

            progress("geometry")
            checked = check_candidate(study, params)
        progress("mesh")
        mesh = tetrahedralize(study, params, checked, settings)
        cache.put("mesh", mkey, mesh)
    progress("fea")
    unit = unit_response(mesh, study, settings)
    cache.put("fea", fkey, unit)
    return unit
