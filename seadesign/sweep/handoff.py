"""spring.json for the chosen candidate: k, its error estimate, design, material, the linear load cases,
and the large-deflection torque curve with its reading at the loads; optionally that curve through self-contact
(`through_contact_row`) where the ranking's path stopped at contact."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pandas as pd

from seadesign.design.spring import SCHEMA_VERSION, write_spring
from seadesign.design.study import Study
from seadesign.run.cache import Cache, digest
from seadesign.sweep.stages import SolverSettings

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
        "torque_curve": handoff_curve(row, study.ranking.contact_is_end_stop),
        "large_deflection": large_deflection_block(row),
        "selection": selection,
        "inputs_hash": inputs_hash,
        "versions": versions,
    }


def curve_to_stop(row: pd.Series) -> tuple[list[float], list[float]]:
    """The row's path points (rad, Nm) up to where it stops, the stop point last: at the impact torque, a limit
    point's maximum (the points past it dropped: the curve increases strictly), contact."""
    theta, torque = list(row["large_curve_rotation_rad"]), list(row["large_curve_torque_Nm"])
    stop_theta, stop_torque = float(row["large_stop_rotation_rad"]), float(row["large_stop_torque_Nm"])
    keep = [i for i, t in enumerate(theta) if t < stop_theta and (i == 0 or torque[i] < stop_torque)]
    rotation, torques = [theta[i] for i in keep], [torque[i] for i in keep]
    if stop_theta > rotation[-1] and stop_torque > torques[-1]:
        rotation.append(stop_theta)
        torques.append(stop_torque)
    return rotation, torques


def handoff_curve(row: pd.Series, contact_is_end_stop: bool) -> dict:
    """The row's torque curve up to where its path stops (`curve_to_stop`); a hard stop when contact is the
    study's end stop."""
    rotation, torques = curve_to_stop(row)
    reason = str(row["large_stop_reason"])
    return {"rotation_rad": rotation, "torque_Nm": torques, "source": "fea_large_deflection", "stop_reason": reason,
            "hard_stop": reason == "contact" and contact_is_end_stop,
            "note": "hyperelastic finite-strain FEA, hub rotated as the servo holds it, ring held; sampled at the "
                    "path's converged increments, interpolated monotonically (PCHIP) by readers"}


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


def through_contact_row(study: Study, row: pd.Series, solver: SolverSettings, cache: Cache) -> pd.Series:
    """The row with its large-deflection columns (`large_`) from its candidate's path through frictionless
    self-contact (the study's `[ranking] self_contact`, on the same path mesh, via the stage cache): what the spring
    does past the gap its ranking's path stopped at. The other columns (the requirements' verdicts among them) stay
    the ranking's."""
    from seadesign.sweep.single import candidate_path  # the path stage's solver: only when asked for
    from seadesign.sweep.table import path_columns

    contact_study = dataclasses.replace(study, ranking=dataclasses.replace(study.ranking, self_contact=True))
    path = candidate_path(contact_study, study.candidate_of_row(row), settings=solver, cache=cache)
    out = row.copy()
    for key, value in path_columns(path.response, contact_study).items():
        out[key] = value
    return out


def through_contact_note(row: pd.Series) -> str:
    """One line on a `through_contact_row`'s curve: first contact, and where and why the path ends (rad, Nm)."""
    first = (f"first contact at {row['large_contact_rotation_rad']:.4f} rad, {row['large_contact_torque_Nm']:.4g} Nm"
             if np.isfinite(row["large_contact_rotation_rad"]) else "the faces never touch")
    return (f"the curve goes on with frictionless self-contact past where the gap closed: {first}; it ends at "
            f"{row['large_stop_rotation_rad']:.4f} rad, {row['large_stop_torque_Nm']:.4g} Nm "
            f"({row['large_stop_reason']})")
