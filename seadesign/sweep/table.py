"""The results table's columns of one candidate, made in one place from the typed stage outputs.

A row is: the candidate (name, one column per design axis, named by its key), its status and
reason, its checked geometry (volume, mass), and, when solved, the linear FEA of both load cases
at the study's torques (`fea.results` columns) with the quantities derived from them here, and the
large-deflection path read at the standing, stall and impact torques (`large_` columns).
Ranking adds its own columns afterwards (`sweep/rank.py`).
"""

from __future__ import annotations

import math

from seadesign.design.candidate import Candidate
from seadesign.design.study import Study
from seadesign.fea.results import columns
from seadesign.sweep.path_stage import PathResponse
from seadesign.sweep.stages import COARSENING, CONVERGENCE_ORDER, CoarseK, UnitResponse


def candidate_columns(candidate: Candidate, row_key: str) -> dict:
    """Name, one column per design axis, status "ok" until a stage says otherwise, the row's key."""
    return {"candidate": candidate.name, **dict(candidate.values), "status": "ok", "reason": "", "row_key": row_key}


def geometry_columns(candidate: Candidate) -> dict:
    """Volume (mm^3) and mass (g) of a checked candidate."""
    return {"volume_mm3": candidate.volume_mm3, "mass_g": candidate.mass_kg * 1e3}


def k_error_columns(coarse: CoarseK | None, k_Nm_per_rad: float) -> dict[str, float]:
    """k on the coarser mesh and k's relative discretization error (NaN: no coarse solve)."""
    k_coarse = math.nan if coarse is None else coarse.k_coarse_Nm_per_rad
    return {
        "k_coarse_Nm_per_rad": k_coarse,
        # two-level Richardson: error of k_h ~ |k_h - k_rh| / (r^p - 1)
        "k_rel_error": abs(k_coarse - k_Nm_per_rad) / k_Nm_per_rad / (COARSENING**CONVERGENCE_ORDER - 1.0),
        "time_error_estimate_s": math.nan if coarse is None else coarse.time_s,
    }


def fea_columns(unit: UnitResponse, coarse: CoarseK | None, study: Study) -> dict[str, float]:
    """Both load cases of the study from the 1 Nm results (the model is linear), units in the names.

    Stall: the servo's stall torque on the hub; the bearing displacement is read on the bearing
    circle (thesis eq. 5.3) and mapped to the foot. Impact: the foot-strike torque on the
    backplate side; reactions are forces on the hub bolts (where the motor attaches).
    """
    lc = study.load_cases
    r = unit.results.at(lc.stall_torque_Nm, lc.impact_torque_Nm)
    k = r.k_Nm_per_rad
    return {
        **r.columns(),
        "time_fea_total_s": unit.time_fea_total_s,
        "impact_rotation_rad": lc.impact_torque_Nm / k,
        "stall_rotation_deg": math.degrees(r.stall.rotation_rad),
        "stall_foot_error_mm": r.stall.bearing_displacement_mm / study.bearing_radius_mm * lc.lower_leg_m * 1e3,
        **k_error_columns(coarse, k),
        "mesh_mean_aspect_ratio": unit.mesh_mean_aspect_ratio,
        "mesh_target_edge_mm": unit.mesh_target_edge_mm,
        "mesh_tetrahedralize_s": unit.mesh_tetrahedralize_s,
    }


def path_columns(path: PathResponse, study: Study) -> dict:
    """The large-deflection columns (`fea.large_deflection`, prefixed `large_`), with the stall bearing
    displacement and foot error read from the path's stall rotation (the hub is rigid: arc length on the
    bearing circle)."""
    out = columns(path.result, "large_")
    rotation = path.result.stall.rotation_rad
    out["large_stall_bearing_displacement_mm"] = rotation * study.bearing_radius_mm
    out["large_stall_foot_error_mm"] = rotation * study.load_cases.lower_leg_m * 1e3
    return out
