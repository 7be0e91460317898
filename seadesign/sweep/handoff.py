"""spring.json for the chosen candidate: k, its error estimate, design, material, the linear load cases,
and the large-deflection torque curve (through self-contact) with its reading at the loads."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pandas as pd

from seadesign.design.spring import SCHEMA_VERSION, write_spring
from seadesign.design.study import Study
from seadesign.run.cache import digest


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
    candidate = study.candidate_of_row(row)
    params = candidate.params
    a, lc, r = study.actuator, study.load_cases, study.robot
    return {
        "schema_version": SCHEMA_VERSION,
        "study": study.name,
        "k_source": "fea",
        "k_Nm_per_rad": float(row["k_Nm_per_rad"]),
        "k_rel_error": _number(row["k_rel_error"]),
        "design": dataclasses.asdict(params),
        "material": candidate.material.to_handoff(),
        "actuator": {
            "stall_torque_Nm": lc.stall_torque_Nm,
            "no_load_speed_rad_per_s": a.no_load_speed_rpm * 2 * math.pi / 60,
            "gear_ratio": a.gear_ratio,
            "backlash_rad": math.radians(a.backlash_deg),
        },
        "robot": {"mass_kg": r.mass_kg, "lower_leg_m": r.lower_leg_m, "upper_leg_m": r.upper_leg_m},
        "load_cases": {case: load_case_block(row, case) for case in ("stall", "impact")},
        "torque_curve": handoff_curve(row),
        "large_deflection": large_deflection_block(row),
        "selection": selection,
        "inputs_hash": inputs_hash,
        "versions": versions,
    }


def curve_to_stop(row: pd.Series) -> tuple[list[float], list[float]]:
    """The row's path points (rad, Nm) up to where it stops, the stop point last: at the impact torque, a limit
    point's maximum (the points past it dropped: the curve increases strictly), the last converged point."""
    theta, torque = list(row["large_curve_rotation_rad"]), list(row["large_curve_torque_Nm"])
    stop_theta, stop_torque = float(row["large_stop_rotation_rad"]), float(row["large_stop_torque_Nm"])
    keep = [i for i, t in enumerate(theta) if t < stop_theta and (i == 0 or torque[i] < stop_torque)]
    rotation, torques = [theta[i] for i in keep], [torque[i] for i in keep]
    if stop_theta > rotation[-1] and stop_torque > torques[-1]:
        rotation.append(stop_theta)
        torques.append(stop_torque)
    return rotation, torques


def handoff_curve(row: pd.Series) -> dict:
    """The row's torque curve up to where its path stops (`curve_to_stop`); no end stop: past contact the curve
    is the path's, through frictionless self-contact."""
    rotation, torques = curve_to_stop(row)
    return {"rotation_rad": rotation, "torque_Nm": torques, "source": "fea_large_deflection",
            "stop_reason": str(row["large_stop_reason"]), "hard_stop": False,
            "note": "hyperelastic finite-strain FEA through frictionless self-contact, hub rotated as the servo holds "
                    "it, ring held; sampled at the path's converged increments, interpolated monotonically (PCHIP) "
                    "by readers"}


def large_deflection_block(row: pd.Series) -> dict:
    """The row's `large_` scalars (prefix dropped, units in the keys); the curve travels in `torque_curve`."""
    out = {}
    for k, v in row.items():
        if not k.startswith("large_") or k.startswith("large_curve_"):
            continue
        out[k[len("large_"):]] = v if isinstance(v, str) else bool(v) if isinstance(v, (bool, np.bool_)) else _number(v)
    return out


def write_handoff(study: Study, t: pd.DataFrame, row: pd.Series, folder: Path, settings: dict,
                  selection: dict) -> Path:
    """spring.json of the chosen row, hashed over every evaluated row and the study's robot data."""
    inputs_hash = digest("spring", list(t["row_key"]), study.ranking, study.requirements, study.robot, study.actuator)
    return write_spring(spring_document(study, row, inputs_hash, settings["versions"], selection), folder / "spring.json")
