"""spring.json for the chosen candidate: k, its error estimate, design, material, load cases."""

from __future__ import annotations

import dataclasses
import math

import pandas as pd

from seadesign.design.spring import SCHEMA_VERSION
from seadesign.design.study import Study

EXTRAPOLATION_NOTE = (
    "linear FEA; beyond {limit:g} rad the beams' rotations are no longer small (sin x ~ x within 0.2 %), "
    "so results at larger rotation are an extrapolation of the linear model"
)


def _number(value) -> float | None:
    v = float(value)
    return None if math.isnan(v) else v


def load_case_block(row: pd.Series, case: str) -> dict[str, float]:
    """The row's numbers of one load case (keys keep their unit suffixes, case prefix dropped)."""
    prefix = f"{case}_"
    return {k[len(prefix):]: _number(v) for k, v in row.items()
            if k.startswith(prefix) and isinstance(v, (int, float)) and not isinstance(v, bool)
            and _number(v) is not None}


def spring_document(study: Study, row: pd.Series, inputs_hash: str, versions: dict[str, str],
                    selection: dict) -> dict:
    """The spring.json content of a chosen, solved candidate (validated by design.spring.write_spring)."""
    params = study.candidate_of_row(row).params
    a, lc, r = study.actuator, study.load_cases, study.robot
    limit = study.ranking.small_deflection_limit_rad
    return {
        "schema_version": SCHEMA_VERSION,
        "study": study.name,
        "k_source": "fea",
        "k_Nm_per_rad": float(row["k_Nm_per_rad"]),
        "k_rel_error": _number(row["k_rel_error"]),
        "design": dataclasses.asdict(params),
        "material": study.material.to_handoff(),
        "actuator": {
            "stall_torque_Nm": lc.stall_torque_Nm,
            "no_load_speed_rad_per_s": a.no_load_speed_rpm * 2 * math.pi / 60,
            "gear_ratio": a.gear_ratio,
            "backlash_rad": math.radians(a.backlash_deg),
        },
        "robot": {"mass_kg": r.mass_kg, "lower_leg_m": r.lower_leg_m, "upper_leg_m": r.upper_leg_m},
        "load_cases": {case: load_case_block(row, case) for case in ("stall", "impact")},
        "extrapolation": {
            "flagged": bool(row["extrapolation"]),
            "threshold_rad": limit,
            "max_rotation_rad": float(row["max_rotation_rad"]),
            "note": EXTRAPOLATION_NOTE.format(limit=limit),
        },
        "selection": selection,
        "inputs_hash": inputs_hash,
        "versions": versions,
    }
