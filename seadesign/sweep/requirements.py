"""Each requirement of a study judged on a results table, as a relative margin, and the objectives.

A margin is >= 0 when the requirement is met (by that fraction of its limit) and < 0 when it is
missed (by that fraction); NaN when it cannot be judged: a load the path does not carry has no strain
to read there (the load's travel requirement fails instead), and a material without a sourced
elongation at yield has no allowable strain. The margins are continuous across each limit, so the
explorer can model them and add the misses up (`total_violation`). Everything but k is read from the
large-deflection path (`large_` columns; `rank.physical_columns`); k is the small-load stiffness,
which the linear solve gives on the finer result mesh (the path's tangent at rest equals it on the
same mesh).

Per requirement (T: the load's torque; travel: the torque where the path stops):
- k range: k / k_min - 1 and 1 - k / k_max;
- standing sag: 1 - sag / limit, or travel / T_standing - 1 when the path stops before the standing load;
- each load carried (no contact or other stop before it): travel / T - 1; zero when contact is the
  study's end stop and carries it;
- the strain at each load: T_strain / T - 1 where the peak strain reaches the allowable at T_strain;
  where it never does on a path that carries the load, allowable / peak strain at the load - 1;
- the envelope: 1 - outer diameter / limit and 1 - axial thickness / limit.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from seadesign.design.study import Study

ACCURACY = "large_stall_bearing_displacement_mm"  # the arc the bearing circle turns through at the stall torque
PROTECTION = "impact_gearbox_torque_Nm"  # the peak torque a foot strike drives into the gearbox
USABLE = "usable_torque_Nm"  # the most a design carries before its path stops and within the allowable strain
OBJECTIVE_COLUMNS = {"mass": "mass_g", "accuracy": ACCURACY, "protection": PROTECTION}
OBJECTIVE_WORDS = {"mass": "mass (g)", "accuracy": "stall bearing arc (mm)", "protection": "strike torque into the gearbox (Nm)"}


@dataclass(frozen=True)
class Requirement:
    """One requirement: its margin column and what it says, in words with its limit."""

    column: str  # "<key>_margin"
    words: str


def requirement_list(study: Study) -> list[Requirement]:
    """The study's requirements in the order they are reported."""
    req, lc = study.requirements, study.load_cases
    torques = {"stall": lc.stall_torque_Nm, "impact": lc.impact_torque_Nm}
    allowable = {m.allowable_strain(study.ranking.safety_factor) for m in study.materials.values()}
    limit = f"{allowable.pop():.3g}" if len(allowable) == 1 and None not in allowable else "the allowable"
    out = []
    for load in req.loads:
        out.append(Requirement(f"{load}_travel_margin", f"carries the {load} torque ({torques[load]:.3g} Nm)"))
    for load in req.loads:
        out.append(Requirement(f"{load}_strain_margin", f"{load} strain < {limit}"))
    out.append(Requirement("standing_margin", f"standing deflection < {req.max_standing_deflection_deg:g} deg"))
    if req.k_min_Nm_per_rad is not None:
        out.append(Requirement("k_min_margin", f"k >= {req.k_min_Nm_per_rad:g} Nm/rad"))
    if req.k_max_Nm_per_rad is not None:
        out.append(Requirement("k_max_margin", f"k <= {req.k_max_Nm_per_rad:g} Nm/rad"))
    if req.max_outer_diameter_mm is not None:
        out.append(Requirement("outer_diameter_margin", f"outer diameter <= {req.max_outer_diameter_mm:g} mm"))
    if req.max_thickness_mm is not None:
        out.append(Requirement("thickness_margin", f"axial thickness <= {req.max_thickness_mm:g} mm"))
    return out


def _col(t: pd.DataFrame, name: str) -> pd.Series:
    return t[name].astype(float) if name in t else pd.Series(np.nan, index=t.index)


def _load_margins(t: pd.DataFrame, load: str, torque_Nm: float, end_stop: bool) -> tuple[pd.Series, pd.Series]:
    """(travel, strain) margins at one load."""
    travel_end = _col(t, "large_stop_torque_Nm")
    carried = _col(t, f"large_{load}_rotation_rad").notna()  # reached, or held by contact as the end stop
    at_end_stop = carried & (travel_end < torque_Nm) if end_stop else pd.Series(False, index=t.index)
    travel = (travel_end / torque_Nm - 1.0).where(~at_end_stop, 0.0)
    crossing = _col(t, "large_strain_limit_torque_Nm")
    strain = (crossing / torque_Nm - 1.0).where(crossing.notna())
    never = crossing.isna() & carried  # allowable / peak - 1 (NaN: no allowable strain)
    strain[never] = (_col(t, "large_allowable_strain") / _col(t, f"large_{load}_peak_strain") - 1.0)[never]
    return travel, strain


def margins(t: pd.DataFrame, study: Study) -> pd.DataFrame:
    """One margin column per requirement (`requirement_list`) for every row; NaN where not solved or not
    judged. `t` has the physical columns (`rank.physical_columns`)."""
    req, lc = study.requirements, study.load_cases
    solved = t["status"] == "ok"
    out = pd.DataFrame(index=t.index)
    torques = {"stall": lc.stall_torque_Nm, "impact": lc.impact_torque_Nm}
    strain = {}
    for load in req.loads:
        out[f"{load}_travel_margin"], strain[load] = _load_margins(t, load, torques[load], study.ranking.contact_is_end_stop)
    for load in req.loads:
        out[f"{load}_strain_margin"] = strain[load]
    sag = _col(t, "standing_deflection_deg")
    standing = study.robot.standing_knee_torque_Nm
    out["standing_margin"] = (1.0 - sag / req.max_standing_deflection_deg).where(
        sag.notna(), _col(t, "large_stop_torque_Nm") / standing - 1.0)
    k = _col(t, "k_Nm_per_rad")
    if req.k_min_Nm_per_rad is not None:
        out["k_min_margin"] = k / req.k_min_Nm_per_rad - 1.0
    if req.k_max_Nm_per_rad is not None:
        out["k_max_margin"] = 1.0 - k / req.k_max_Nm_per_rad
    if req.max_outer_diameter_mm is not None or req.max_thickness_mm is not None:
        env = envelope(t, study)
        if req.max_outer_diameter_mm is not None:
            out["outer_diameter_margin"] = 1.0 - env["outer_diameter_mm"] / req.max_outer_diameter_mm
        if req.max_thickness_mm is not None:
            out["thickness_margin"] = 1.0 - env["axial_thickness_mm"] / req.max_thickness_mm
    return out.where(solved)


def envelope(t: pd.DataFrame, study: Study) -> pd.DataFrame:
    """Outer diameter and axial thickness (mm) of each row's design."""
    params = [study.candidate_of_row(r).params for _, r in t.iterrows()]
    return pd.DataFrame({"outer_diameter_mm": [2 * p.ring_outer_radius_mm for p in params],
                         "axial_thickness_mm": [p.thickness_mm for p in params]}, index=t.index)


def total_violation(m: pd.DataFrame) -> pd.Series:
    """Sum of the fractions by which the requirements are missed (requirements not judged add nothing)."""
    return (-m).clip(lower=0.0).fillna(0.0).sum(axis=1)
