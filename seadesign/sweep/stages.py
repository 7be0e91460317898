"""The per-candidate stages of a sweep: geometry -> validity -> mesh -> unit FEA -> load cases.

Each expensive stage is cached under a key made of its inputs and the previous stage's key,
so changing one input recomputes only the stages that depend on it. The FEA is solved once
for 1 Nm of hub torque (ring held); both load cases are that response scaled, since the
model is linear (see seadesign/fea/torsion.py).

Meshing is `seadesign.mesh.mesh_part`, the solve `seadesign.fea.loadcases.analyse` at 1 Nm per
load case; a second P2 solve on a mesh COARSENING times coarser gives the discretization-error
estimate of k (two-level Richardson at CONVERGENCE_ORDER, the smallest order observed in
benchmarks/fea_convergence.py).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np

from seadesign.run.cache import Cache, digest, package_versions
from seadesign.design.params import GeometryParams
from seadesign.design.study import Study

Progress = Callable[[str], None]  # receives the name of the stage that starts
COARSENING = 1.5  # edge-length ratio of the error-estimate mesh to the result mesh
CONVERGENCE_ORDER = 1.1  # smallest order of k observed in benchmarks/fea_convergence.py (1.10-1.89)


@dataclass(frozen=True)
class SolverSettings:
    """Numerical settings that change results (part of every FEA cache key)."""

    element_order: int = 2  # P2 tetrahedra
    linear_solver: str = "pardiso"  # "pardiso" or "scipy"


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
    """FEA results for 1 Nm in each load case (seadesign.fea.loadcases.analyse with unit torques)
    plus vertex fields for renders; everything scales linearly with the applied torque."""

    per_Nm: dict  # analyse(...).results at stall = impact = 1 Nm (units in the keys, per Nm)
    k_coarse_Nm_per_rad: float  # k on a COARSENING times coarser mesh (error estimate of k)
    points_mm: np.ndarray  # (n, 3) mesh vertices
    tets: np.ndarray  # (m, 4)
    vertex_displacement_m: dict  # case -> (n, 3) displacement in m per Nm
    vertex_von_mises_Pa: np.ndarray  # (n,) von Mises in Pa per Nm (same for both cases)
    mesh_info: dict  # quality and how the mesh was made


def geometry_key(study: Study, params: GeometryParams) -> str:
    return digest("geometry", params, study.validity, package_versions(("seadesign", "cadquery")))


def mesh_key(study: Study, params: GeometryParams) -> str:
    """Inputs of the mesh (the mesh package keys its own cache by the surface it receives)."""
    return digest("mesh", geometry_key(study, params), study.mesh, package_versions(("pytetwild", "gmsh")))


def fea_key(study: Study, params: GeometryParams, settings: SolverSettings) -> str:
    m = study.material
    return digest("fea", mesh_key(study, params), m.youngs_modulus_Pa, m.poisson_ratio,
                  settings.element_order, settings.linear_solver, package_versions())


def check_geometry(study: Study, params: GeometryParams, cache: Cache) -> tuple[Geometry, object | None]:
    """Geometry verdict (cached) and the built CheckedPart when it had to be built (else None)."""
    key = geometry_key(study, params)
    hit = cache.get("geometry", key)
    if hit is not None:
        return hit, None
    from seadesign.design.candidate import check_candidate

    checked = check_candidate(study, params)
    geo = Geometry(tuple(checked.reasons), float(checked.part.volume_mm3))
    cache.put("geometry", key, geo)
    return geo, checked


def tetrahedralize(study: Study, params: GeometryParams, checked, cache: Cache, coarsening: float = 1.0):
    """Tetrahedral mesh (mm) of a checked part with named interface boundaries (mesh package,
    its own content-addressed cache under the sweep cache's root); `coarsening` > 1 makes the
    elements that many times longer (beam, curvature and layer sizing alike)."""
    from seadesign.mesh import mesh_part

    return mesh_part(checked.part.solid, checked.part.interfaces, beam_width_mm=params.beam_thickness_mm,
                     cache_dir=Path(cache.root) / "mesh", **study.mesh.scaled(1.0 / coarsening).mesh_part_options())


def unit_response(mesh, coarse_mesh, study: Study, settings: SolverSettings) -> UnitResponse:
    """Both load cases at 1 Nm, and k on the coarse mesh for the error estimate."""
    from seadesign.fea.loadcases import analyse
    from seadesign.fea.stress import invariants
    from seadesign.fea.torsion import solve_unit_torsion

    m = study.material
    t0 = time.perf_counter()
    a = analyse(mesh, m.youngs_modulus_Pa, m.poisson_ratio, m.yield_strength_Pa, 1.0, 1.0, study.bearing_radius_mm,
                order=settings.element_order, linear_solver=settings.linear_solver)
    t1 = time.perf_counter()
    coarse = solve_unit_torsion(coarse_mesh, m.youngs_modulus_Pa, m.poisson_ratio, order=settings.element_order,
                                linear_solver=settings.linear_solver)
    nv = a.unit.emesh.n_vertices
    return UnitResponse(
        per_Nm={**a.results, "time_fea_total_s": t1 - t0, "time_error_estimate_s": time.perf_counter() - t1},
        k_coarse_Nm_per_rad=1.0 / float(coarse.hub_motion[5]),
        points_mm=mesh.points_mm,
        tets=mesh.tets,
        vertex_displacement_m={case: a.displacement_m(case)[:nv] for case in ("stall", "impact")},
        vertex_von_mises_Pa=invariants(a.stress_per_Nm_Pa[:nv])["von_mises"],
        mesh_info={**mesh.quality.as_dict(), "mesh_target_edge_mm": mesh.info.get("target_edge_mm", float("nan")),
                   "mesh_tetrahedralize_s": mesh.info.get("tetrahedralize_s", float("nan"))},
    )


def _scaled_keys(case: str) -> tuple[str, ...]:
    """Result keys of one load case that are linear in its torque."""
    from seadesign.fea.loadcases import STRESS_NAMES

    stresses = tuple(f"{case}_{n}_{'min' if n == 'principal_3' else 'max'}_MPa" for n in STRESS_NAMES)
    if case == "stall":
        return ("stall_rotation_rad", "stall_bearing_displacement_mm") + stresses
    return ("impact_reaction_per_bolt_N", "impact_reaction_per_bolt_min_N", "impact_peak_nodal_reaction_N") + stresses


def load_case_columns(unit: UnitResponse, study: Study) -> dict[str, float]:
    """Both load cases of the study from the 1 Nm results (the model is linear), units in the names.

    Stall: the servo's stall torque on the hub; the bearing displacement is read on the bearing
    circle (thesis eq. 5.3) and mapped to the foot. Impact: the foot-strike torque on the
    backplate side; reactions are forces on the hub bolts (where the motor attaches).
    """
    lc, m = study.load_cases, study.material
    out = dict(unit.per_Nm)
    torques = {"stall": lc.stall_torque_Nm, "impact": lc.impact_torque_Nm}
    for case, torque in torques.items():
        out[f"{case}_torque_Nm"] = torque
        for key in _scaled_keys(case):
            out[key] = unit.per_Nm[key] * torque
        out[f"{case}_safety_factor"] = m.yield_strength_Pa / (out[f"{case}_von_mises_max_MPa"] * 1e6)
    k = out["k_Nm_per_rad"]
    out["impact_rotation_rad"] = lc.impact_torque_Nm / k
    out["safety_factor"] = min(out["stall_safety_factor"], out["impact_safety_factor"])
    out["stall_rotation_deg"] = math.degrees(out["stall_rotation_rad"])
    out["stall_foot_error_mm"] = out["stall_bearing_displacement_mm"] / study.bearing_radius_mm * lc.lower_leg_m * 1e3
    out["k_coarse_Nm_per_rad"] = unit.k_coarse_Nm_per_rad
    # two-level Richardson: error of k_h ~ |k_h - k_rh| / (r^p - 1)
    out["k_rel_error"] = abs(unit.k_coarse_Nm_per_rad - k) / k / (COARSENING**CONVERGENCE_ORDER - 1.0)
    out.update(unit.mesh_info)
    return out


def fea_response(study: Study, params: GeometryParams, checked, settings: SolverSettings, cache: Cache,
                 progress: Progress) -> UnitResponse:
    """Unit response via the cache: the mesh (cached) is made only when the solve is not cached."""
    fkey = fea_key(study, params, settings)
    unit = cache.get("fea", fkey)
    if unit is not None:
        return unit
    if checked is None:
        from seadesign.design.candidate import check_candidate

        progress("geometry")
        checked = check_candidate(study, params)
    progress("mesh")
    mesh = tetrahedralize(study, params, checked, cache)
    coarse_mesh = tetrahedralize(study, params, checked, cache, COARSENING)
    progress("fea")
    unit = unit_response(mesh, coarse_mesh, study, settings)
    cache.put("fea", fkey, unit)
    return unit
