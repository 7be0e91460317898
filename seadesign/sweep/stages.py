"""The per-candidate stages of a sweep: geometry -> validity -> mesh -> unit FEA -> load cases.

Each stage takes and returns typed objects (`Candidate`, `TetMesh`, `UnitResponse`). Each
expensive stage is cached under a key made of its inputs and the previous stage's key, so
changing one input recomputes only the stages that depend on it. The FEA is solved once for
1 Nm of hub torque (ring held); both load cases are that response scaled by the rules of
`fea.results`, since the model is linear (see seadesign/fea/torsion.py). The results table's
columns are made from these objects in `sweep/table.py`.

Meshing is `seadesign.mesh.mesh_part`, the solve `seadesign.fea.loadcases.analyse` at 1 Nm per
load case; a second P2 solve on a mesh COARSENING times coarser (`coarse_k`, a stage of its own)
gives the discretization-error estimate of k (two-level Richardson at CONVERGENCE_ORDER, the smallest
order observed in benchmarks/fea_convergence.py).

Both linear solves are made and cached at REFERENCE_MODULUS_PA and scaled to the material's modulus by
the rules of `fea.results` (k as E; rotations and displacements as 1 / E; stresses and reactions do not
change): a sweep whose only change is the modulus, a calibrated one, reuses them.
"""

from __future__ import annotations

import functools
import time
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Callable


from seadesign.design.candidate import Candidate
from seadesign.design.study import Study
from seadesign.run.cache import Cache, digest, package_versions
from seadesign.run.fingerprint import code_fingerprint
from seadesign.run.heavy_stage import heavy_stage

if TYPE_CHECKING:
    from seadesign.design.geometry import Part
    from seadesign.fea.results import LinearResults

Progress = Callable[[str], None]  # receives the name of the stage that starts
COARSENING = 1.5  # edge-length ratio of the error-estimate mesh to the result mesh
CONVERGENCE_ORDER = 1.1  # smallest order of k observed in benchmarks/fea_convergence.py (1.10-1.89)
REFERENCE_MODULUS_PA = 1e7  # Young's modulus of the cached linear solves (Pa), of a TPU's order


@dataclass(frozen=True)
class SolverSettings:
    """Numerical settings that change results (part of every FEA cache key)."""

    element_order: int = 2  # P2 tetrahedra
    linear_solver: str = "pardiso"  # "pardiso" or "scipy"
    path_layers: int = 1  # layers through the thickness of the large-deflection path's mesh (a prismatic part's):
    # its in-plane sizing is the result mesh's, which resolves the beam-root fillets where contact and
    # creases start; a coarser path mesh puts contact late (docs/validation/mesh-convergence.md)
    path_formulation: str = "full"  # volumetric formulation of the path (fea.finite_strain), as CalculiX's C3D10
    k_error_estimate: bool = True  # solve k on a COARSENING times coarser mesh too (k's discretization error,
    # `coarse_k`); the explorer, which judges designs on their paths, makes it only for the design it reports


@dataclass(frozen=True)
class UnitResponse:
    """The FEA of one candidate at 1 Nm in each load case (scale with `results.at`) and how the mesh
    and solve went."""

    results: LinearResults  # both load cases at 1 Nm
    time_fea_total_s: float
    mesh_mean_aspect_ratio: float
    mesh_target_edge_mm: float
    mesh_tetrahedralize_s: float


@dataclass(frozen=True)
class CoarseK:
    """k on a COARSENING times coarser mesh: with the result mesh's k, the error estimate of k."""

    k_coarse_Nm_per_rad: float
    time_s: float


def geometry_key(study: Study, candidate: Candidate) -> str:
    """Inputs of the geometry verdict: the parameters, the rules, the CAD code and kernel."""
    return digest("geometry", candidate.params, study.validity, code_fingerprint("seadesign.design.candidate"),
                  package_versions(("cadquery",)))


def mesh_key(study: Study, candidate: Candidate) -> str:
    """Inputs of the mesh (the mesh package keys its own cache by the surface it receives)."""
    return digest("mesh", geometry_key(study, candidate), study.mesh,
                  code_fingerprint("seadesign.mesh", "seadesign.mesh.worker"), package_versions(("pytetwild", "gmsh")))


def fea_key(study: Study, candidate: Candidate, settings: SolverSettings) -> str:
    """Inputs of the unit response at REFERENCE_MODULUS_PA: the mesh, the material's Poisson ratio and yield
    strength, the solver settings, and the code of this module with everything it imports (the solver, the
    mesher, the study's mesh sizing)."""
    m = candidate.material
    return digest("fea", mesh_key(study, candidate), REFERENCE_MODULUS_PA, m.poisson_ratio, m.yield_strength_Pa,
                  settings.element_order, settings.linear_solver,
                  code_fingerprint("seadesign.sweep.stages", "seadesign.mesh.worker"), package_versions())


def coarse_k_key(study: Study, candidate: Candidate, settings: SolverSettings) -> str:
    """Inputs of the coarse k: those of the unit response and the coarsening."""
    return digest("coarse_k", fea_key(study, candidate, settings), COARSENING)


def check_geometry(study: Study, candidate: Candidate, cache: Cache) -> tuple[Candidate, Part | None]:
    """The checked candidate (verdict and volume cached) and its CAD part when it had to be built."""
    key = geometry_key(study, candidate)
    hit = cache.get("geometry", key)
    if hit is not None:
        reasons, volume_mm3 = hit
        return candidate.with_geometry(reasons, volume_mm3), None
    checked, part = study.check(candidate)
    cache.put("geometry", key, (checked.reasons, checked.volume_mm3))
    return checked, part


def tetrahedralize(study: Study, candidate: Candidate, part: Part, cache: Cache, coarsening: float = 1.0,
                   layers: int | None = None):
    """Tetrahedral mesh (mm) of a built part with named interface boundaries (mesh package,
    its raw meshes in the same stage cache); `coarsening` > 1 makes the
    elements that many times longer (beam, curvature and layer sizing alike); `layers` replaces the
    study's layers through a prismatic part's thickness."""
    from seadesign.mesh import mesh_part

    options = study.mesh.scaled(1.0 / coarsening).mesh_part_options()
    if layers is not None:
        options["layers"] = layers
    return mesh_part(part.solid, part.interfaces, beam_width_mm=candidate.params.beam_thickness_mm,
                     cache_dir=cache.root, **options)


def unit_response(mesh, study: Study, candidate: Candidate, settings: SolverSettings) -> UnitResponse:
    """Both load cases at 1 Nm, at REFERENCE_MODULUS_PA."""
    from seadesign.fea.loadcases import analyse

    m = candidate.material
    t0 = time.perf_counter()
    a = analyse(mesh, REFERENCE_MODULUS_PA, m.poisson_ratio, m.yield_strength_Pa, 1.0, 1.0, study.bearing_radius_mm,
                order=settings.element_order, linear_solver=settings.linear_solver)
    return UnitResponse(
        results=a.results,
        time_fea_total_s=time.perf_counter() - t0,
        mesh_mean_aspect_ratio=mesh.quality.mean_aspect_ratio,
        mesh_target_edge_mm=mesh.info.get("target_edge_mm", float("nan")),
        mesh_tetrahedralize_s=mesh.info.get("tetrahedralize_s", float("nan")),
    )


def part_source(study: Study, candidate: Candidate, built: Part | None, progress: Progress) -> Callable[[], Part]:
    """The candidate's CAD part as a function: `built` when the geometry stage made it, else built on the
    first call (only a stage whose result is not cached asks), once."""

    @functools.cache
    def part() -> Part:
        if built is not None:
            return built
        progress("geometry")
        return study.check(candidate)[1]

    return part


def fea_response(study: Study, candidate: Candidate, part: Callable[[], Part], settings: SolverSettings, cache: Cache,
                 progress: Progress) -> UnitResponse:
    """Unit response at the material's modulus via the cache: the part and the mesh (cached) are made only
    when the solve is not cached."""
    fkey = fea_key(study, candidate, settings)
    unit = cache.get("fea", fkey)
    if unit is None:
        progress("mesh")
        mesh = tetrahedralize(study, candidate, part(), cache)
        progress("fea")
        with heavy_stage():  # the sweep's largest factorization: one worker at a time
            unit = unit_response(mesh, study, candidate, settings)
        cache.put("fea", fkey, unit)
    return replace(unit, results=unit.results.with_modulus(candidate.material.youngs_modulus_Pa / REFERENCE_MODULUS_PA))


def coarse_k(study: Study, candidate: Candidate, part: Callable[[], Part], settings: SolverSettings, cache: Cache,
             progress: Progress) -> CoarseK:
    """k on the COARSENING times coarser mesh via the cache (its own stage: the explorer asks for it only for
    the design it reports)."""
    from seadesign.fea.torsion import solve_unit_torsion

    key = coarse_k_key(study, candidate, settings)
    result = cache.get("coarse_k", key)
    if result is None:
        progress("mesh")
        mesh = tetrahedralize(study, candidate, part(), cache, COARSENING)
        progress("fea")
        t0 = time.perf_counter()
        coarse = solve_unit_torsion(mesh, REFERENCE_MODULUS_PA, candidate.material.poisson_ratio,
                                    order=settings.element_order, linear_solver=settings.linear_solver)
        result = CoarseK(1.0 / float(coarse.hub_motion[5]), time.perf_counter() - t0)
        cache.put("coarse_k", key, result)
    return replace(result, k_coarse_Nm_per_rad=result.k_coarse_Nm_per_rad * candidate.material.youngs_modulus_Pa
                   / REFERENCE_MODULUS_PA)
