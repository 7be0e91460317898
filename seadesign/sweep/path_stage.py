"""The large-deflection stage of a sweep: a candidate's torque path, read at its loads.

The path (`fea.rotation_path`, the material's hyperelastic law) runs from rest to the study's impact
torque or to where it stops, on the result mesh's in-plane sizing with `SolverSettings.path_layers`
layers through the thickness (its error against the result mesh is in docs/validation/mesh-convergence.md). `fea.large_deflection`
reads it at the standing, stall and impact torques. The result is cached under the mesh, the law,
the path settings, the torques, the strain limits and the code.

A material calibrated by a stiffness scale s (`Material.scaled`) has the path of the material it was scaled
from driven to the loads over s, its torques times s (`fea.path_scale`): read from that material's path when the
cache holds it and its points are those (it stopped before its impact torque for a reason no scale moves, and its
render's state is the same point), else solved. Either way the numbers are the same to the last digit: they depend
on the inputs only, not on what the cache holds.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Callable

import numpy as np

from seadesign.design.candidate import Candidate
from seadesign.design.materials import Hyperelastic
from seadesign.design.study import Study
from seadesign.fea.finite_strain import Solid
from seadesign.fea.large_deflection import LargeDeflection, large_deflection
from seadesign.fea.path_scale import scaled_path
from seadesign.fea.rotation_path import PathSettings, rotation_path, through_contact
from seadesign.fea.torque_path import TorquePath
from seadesign.run.cache import Cache, digest, package_versions
from seadesign.run.fingerprint import code_fingerprint
from seadesign.sweep.stages import Progress, SolverSettings, mesh_key, tetrahedralize

if TYPE_CHECKING:
    from seadesign.design.geometry import Part


@dataclass(frozen=True)
class PathResponse:
    """The path read at the loads, and the state a render shows: the first point that carries the stall
    torque, or the last point when the path stops before it."""

    result: LargeDeflection
    points_mm: np.ndarray  # (n, 3) vertices of the path mesh
    tets: np.ndarray  # (m, 4)
    vertex_displacement_m: np.ndarray  # (n, 3) at the snapshot
    vertex_strain: np.ndarray  # (n,) largest tensile principal engineering strain of the elements at each vertex
    snapshot_rotation_rad: float
    snapshot_torque_Nm: float
    path: TorquePath  # the path's points, stop and events, without its states (what a scaled law reads again)


PATH_SETTINGS = through_contact(PathSettings())  # the sweep's path goes on through frictionless self-contact


def path_key(study: Study, candidate: Candidate, settings: SolverSettings) -> str:
    """Inputs of the path: the mesh, the law, the path's mesh and settings, the torques, the strain limits
    and the code of this module with everything it imports."""
    lc = study.load_cases
    return digest("path", mesh_key(study, candidate), candidate.material.law, settings.path_layers,
                  settings.path_formulation, PATH_SETTINGS, study.robot.standing_knee_torque_Nm, lc.stall_torque_Nm,
                  lc.impact_torque_Nm, candidate.material.strain_limits(study.ranking.safety_factor),
                  code_fingerprint(__name__), package_versions())


def path_response(study: Study, candidate: Candidate, part: Callable[[], Part], settings: SolverSettings, cache: Cache,
                  progress: Progress) -> PathResponse:
    """The candidate's path via the cache (the part and the mesh are made only on a miss)."""
    key = path_key(study, candidate, settings)
    hit = cache.get("path", key)
    if hit is not None:
        return hit
    base, s = candidate.material, 1.0
    scale = None if base.scaled_from is None else base.law.scale_of(base.scaled_from.law)
    if scale is not None:
        base, s = base.scaled_from, scale
    lc, gap = study.load_cases, PATH_SETTINGS.contact_gap_mm
    unscaled = None if s == 1.0 else cache.get("path", path_key(study, replace(candidate, material=base), settings))
    path = None if unscaled is None else scaled_path(unscaled.path, s, lc.impact_torque_Nm, gap, lc.stall_torque_Nm)
    if path is not None:  # the uncalibrated path's points are this one's
        response = replace(unscaled, result=_read(study, candidate, path),
                           snapshot_torque_Nm=path.points[path.snapshot_index].torque_Nm, path=path)
    else:
        response = _solved_response(study, candidate, base.law, s, part, settings, cache, progress)
    cache.put("path", key, response)
    return response


def _read(study: Study, candidate: Candidate, path: TorquePath) -> LargeDeflection:
    """The path read at the study's loads."""
    lc = study.load_cases
    return large_deflection(path, study.robot.standing_knee_torque_Nm, lc.stall_torque_Nm, lc.impact_torque_Nm,
                            candidate.material.strain_limits(study.ranking.safety_factor))


def _solved_response(study: Study, candidate: Candidate, law: Hyperelastic, s: float, part: Callable[[], Part],
                     settings: SolverSettings, cache: Cache, progress: Progress) -> PathResponse:
    """The candidate's path solved on the path mesh under `law` times `s` (`law` driven to the loads over s)."""
    progress("mesh")
    mesh = tetrahedralize(study, candidate, part(), cache, layers=settings.path_layers)
    progress("path")
    lc = study.load_cases
    path = rotation_path(mesh, law, lc.impact_torque_Nm / s, PATH_SETTINGS, order=settings.element_order,
                         formulation=settings.path_formulation, snapshot_torque_Nm=lc.stall_torque_Nm / s)
    if s != 1.0:  # serves by construction: driven to the loads over s
        path = scaled_path(path, s, lc.impact_torque_Nm, PATH_SETTINGS.contact_gap_mm, lc.stall_torque_Nm)
    result = _read(study, candidate, path)
    tensile = Solid.of(path.emesh, law, settings.path_formulation).element_strain_stress(
        path.snapshot_displacement_m).tensile_strain
    nv = len(mesh.points_mm)
    vertex_strain = np.zeros(nv)
    np.maximum.at(vertex_strain, mesh.tets, tensile[:, None])
    shot = path.points[path.snapshot_index]
    return PathResponse(result, mesh.points_mm, mesh.tets, path.snapshot_displacement_m[:nv], vertex_strain,
                        shot.rotation_rad, shot.torque_Nm,
                        replace(path, displacement_m=None, snapshot_displacement_m=None))
