"""Results-table rows of hand-made springs with closed-form curves, written apart from the ranking code: a
linear curve T = k theta up to the impact torque (or a stop), a tensile strain growing as strain_per_rad x
theta, and every `large_` column the ranking reads, computed by hand."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pandas as pd

from seadesign.design.study import Study


def with_limits(study: Study, cyclic: float | None, elongation: float | None = 0.65) -> Study:
    """The study with its one material's cyclic strain limit and elongation at yield set."""
    m = study.material
    return study.with_materials({m.key: dataclasses.replace(m, cyclic_strain_limit=cyclic,
                                                            elongation_at_yield=elongation)})


def linear_row(study: Study, i: int, name: str, k: float, strain_per_rad: float, stop_Nm: float | None = None,
               mass_g: float = 20.0, reason: str = "unconverged") -> dict:
    """A solved candidate with T = k theta to the impact torque, or to `stop_Nm` (stop `reason`)."""
    lc, m = study.load_cases, study.material
    cyclic = math.nan if m.cyclic_strain_limit is None else m.cyclic_strain_limit
    single = math.nan if m.elongation_at_yield is None else m.elongation_at_yield / study.ranking.safety_factor
    stop = lc.impact_torque_Nm if stop_Nm is None else stop_Nm
    theta = np.linspace(0.0, stop / k, 9)
    row = {"candidate": name, "beam_count": i + 3, "beam_thickness_mm": 6.0, "status": "ok", "reason": "",
           "row_key": f"{i:032x}", "k_Nm_per_rad": k, "mass_g": mass_g,
           "large_curve_rotation_rad": list(theta), "large_curve_torque_Nm": list(k * theta),
           "large_curve_tangent_Nm_per_rad": [k] * len(theta),
           "large_stop_reason": "target_reached" if stop_Nm is None else reason,
           "large_stop_rotation_rad": stop / k, "large_stop_torque_Nm": stop,
           "large_cyclic_strain_limit": cyclic, "large_single_strain_limit": single}
    for kind, limit in (("cyclic", cyclic), ("single", single)):
        cross = limit / strain_per_rad
        inside = math.isfinite(cross) and k * cross <= stop
        row[f"large_{kind}_limit_rotation_rad"] = cross if inside else math.nan
        row[f"large_{kind}_limit_torque_Nm"] = k * cross if inside else math.nan
    for case, torque in (("standing", study.robot.standing_knee_torque_Nm), ("stall", lc.stall_torque_Nm),
                         ("impact", lc.impact_torque_Nm)):
        rot = torque / k if torque <= stop else math.nan
        row[f"large_{case}_rotation_rad"] = rot
        row[f"large_{case}_tensile_strain"] = strain_per_rad * rot
        row[f"large_{case}_strain_limit"] = single if case == "impact" else cyclic
    row["large_stall_secant_k_Nm_per_rad"] = k
    row["large_stall_bearing_displacement_mm"] = row["large_stall_rotation_rad"] * study.bearing_radius_mm
    return row


def table(study: Study, rows: list[tuple], invalid: bool = True) -> pd.DataFrame:
    """Rows of `linear_row` (name, k, strain per rad[, stop torque[, mass]]) and one invalid design, G."""
    t = pd.DataFrame([linear_row(study, i, *r) for i, r in enumerate(rows)])
    if not invalid:
        return t
    g = {"candidate": "G", "beam_count": 10, "beam_thickness_mm": 8.0, "status": "invalid", "reason": "beams touch",
         "row_key": "f" * 32}
    return pd.concat([t, pd.DataFrame([g])], ignore_index=True)
