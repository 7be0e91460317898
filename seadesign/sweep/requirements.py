"""Each requirement of a study judged on a results table, as a relative margin, and the objectives.

A margin is >= 0 when the requirement is met (by that fraction of its limit) and < 0 when it is
missed (by that fraction); NaN when it cannot be judged: a load the path does not carry has no strain
to read there (the load's travel requirement fails instead), and a material without a sourced strain limit
for a load's class has no allowable strain there. A requirement that cannot be judged is not met
(`rank.constraint_columns`); `not_judged` says which datum is missing and the value it must reach. The
margins are continuous across each limit, so the explorer can model them and add the misses up
(`total_violation`). Everything but the explicit k range is read from the large-deflection path (`large_`
columns; `physical.physical_columns`); that range bounds the small-load k, which the linear solve gives on the
finer result mesh (the path's tangent at rest equals it on the same mesh).

Per requirement (T: the load's torque; travel: the torque where the path stops; the working range: rest to
the stall torque, or to the stop when the path stops before it):
- standing sag: 1 - sag / limit, or travel / T_standing - 1 when the path stops before the standing load;
- foot error at stall: 1 - lower leg x stall rotation / limit, or travel / T_stall - 1;
- sensor resolution: 1 - the working range's largest tangent x one count (rad) / limit;
- natural frequency: sqrt(the working range's smallest tangent / J) / 2 pi / limit - 1;
- strike torque: 1 - strike torque / limit; where the curve stops before storing the strike's energy, the
  smaller of 1 - stop torque / limit and stored energy / strike energy - 1 (a miss);
- k range: k / k_min - 1 and 1 - k / k_max;
- each load carried (no contact or other stop before it): travel / T - 1; zero when contact is the
  study's end stop and carries it;
- the tensile strain at each load against its class's limit (stall: cyclic, impact: single-event):
  T_limit / T - 1 where the tensile strain reaches the limit at T_limit; where it never does on a path that
  carries the load, limit / strain at the load - 1;
- the envelope: 1 - outer diameter / limit and 1 - axial thickness / limit.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pandas as pd

from seadesign.design.materials import Material
from seadesign.design.requirements import RAD_PER_COUNT
from seadesign.design.study import Study

ACCURACY = "large_stall_bearing_displacement_mm"  # the arc the bearing circle turns through at the stall torque
PROTECTION = "impact_gearbox_torque_Nm"  # the peak torque a foot strike drives into the gearbox
USABLE = "usable_torque_Nm"  # the most a design carries before its path stops and within the cyclic strain limit
STRAIN_USE = "strain_use"  # the largest share of a load's strain limit its tensile strain uses (1: at the limit)
OBJECTIVE_COLUMNS = {"mass": "mass_g", "accuracy": ACCURACY, "protection": PROTECTION, "strain_margin": STRAIN_USE,
                     "softest_k": "k_Nm_per_rad"}
OBJECTIVE_WORDS = {"mass": "mass (g)", "accuracy": "stall bearing arc (mm)",
                   "protection": "strike torque into the gearbox (Nm)",
                   "strain_margin": "share of the strain limit used (-)", "softest_k": "small-load k (Nm/rad)"}
LOAD_CLASS = {"stall": ("cyclic", "cyclic strain limit"), "impact": ("single", "elongation at yield")}
# The path mesh (the result mesh's in-plane sizing, one layer through the thickness) reaches a tensile strain at a
# higher torque than the default mesh, by a factor of up to 1 / 0.951 on the designs measured
# (`benchmarks/path_convergence.py --strain-levels`; the table is in docs/validation/mesh-convergence.md). The path's torques at a strain limit are multiplied by 0.95, and its strains at a load
# divided by it (the same statement to first order), so that a verdict read on the path mesh holds on the
# default mesh (`tests/test_strain_knockdown.py`, marked default_mesh).
STRAIN_TORQUE_KNOCKDOWN = 0.95


@dataclass(frozen=True)
class Requirement:
    """One requirement: its margin column and what it says, in words with its limit."""

    column: str  # "<key>_margin"
    words: str


def requirement_list(study: Study) -> list[Requirement]:
    """The study's requirements in the order they are reported."""
    req, lc = study.requirements, study.load_cases
    torques = {"stall": lc.stall_torque_Nm, "impact": lc.impact_torque_Nm}
    out = [Requirement(f"{load}_travel_margin", f"carries the {load} torque ({torques[load]:.3g} Nm)")
           for load in req.loads]
    for load in req.loads:
        kind = "cyclic" if LOAD_CLASS[load][0] == "cyclic" else "single-event"
        out.append(Requirement(f"{load}_strain_margin", f"{load} tensile strain within the {kind} limit"))
    for column, limit, words in (
            ("standing_margin", req.max_standing_deflection_deg, "standing deflection <= {:g} deg"),
            ("foot_error_margin", req.max_stall_foot_error_mm, "foot error at stall <= {:g} mm"),
            ("torque_resolution_margin", req.max_torque_per_count_Nm, "one sensor count <= {:g} Nm"),
            ("natural_frequency_margin", req.min_natural_frequency_Hz, "natural frequency >= {:g} Hz"),
            ("strike_margin", req.max_strike_torque_Nm, "strike torque into the gearbox <= {:g} Nm"),
            ("k_min_margin", req.k_min_Nm_per_rad, "k >= {:g} Nm/rad"),
            ("k_max_margin", req.k_max_Nm_per_rad, "k <= {:g} Nm/rad"),
            ("outer_diameter_margin", req.max_outer_diameter_mm, "outer diameter <= {:g} mm"),
            ("thickness_margin", req.max_thickness_mm, "axial thickness <= {:g} mm")):
        if limit is not None:
            out.append(Requirement(column, words.format(limit)))
    return out


def _col(t: pd.DataFrame, name: str) -> pd.Series:
    return t[name].astype(float) if name in t else pd.Series(np.nan, index=t.index)


def tensile_strain(t: pd.DataFrame, load: str) -> pd.Series:
    """The tensile strain at a load, read from the path and knocked up by 1 / STRAIN_TORQUE_KNOCKDOWN."""
    return _col(t, f"large_{load}_tensile_strain") / STRAIN_TORQUE_KNOCKDOWN


def limit_torque(t: pd.DataFrame, kind: str) -> pd.Series:
    """The torque (Nm) where the tensile strain reaches the `kind` ("cyclic", "single") limit, read from the path
    and knocked down by STRAIN_TORQUE_KNOCKDOWN (NaN: never on the path)."""
    return _col(t, f"large_{kind}_limit_torque_Nm") * STRAIN_TORQUE_KNOCKDOWN


def _load_margins(t: pd.DataFrame, load: str, torque_Nm: float) -> tuple[pd.Series, pd.Series]:
    """(travel, strain) margins at one load, the strain against the load class's limit."""
    travel = _col(t, "large_stop_torque_Nm") / torque_Nm - 1.0
    carried = _col(t, f"large_{load}_rotation_rad").notna()
    crossing = limit_torque(t, LOAD_CLASS[load][0])
    strain = (crossing / torque_Nm - 1.0).where(crossing.notna())
    never = crossing.isna() & carried  # limit / strain - 1 (NaN: no sourced limit)
    strain[never] = (_col(t, f"large_{load}_strain_limit") / tensile_strain(t, load) - 1.0)[never]
    return travel, strain


def working_tangents(row: pd.Series, stall_torque_Nm: float) -> np.ndarray:
    """The path's tangent stiffness (Nm/rad) at its points up to the stall torque (and at it, interpolated)."""
    if not isinstance(row.get("large_curve_torque_Nm"), (list, tuple, np.ndarray)):
        return np.array([])
    torque = np.asarray(row["large_curve_torque_Nm"], float)
    tangent = np.asarray(row["large_curve_tangent_Nm_per_rad"], float)
    inside = torque <= stall_torque_Nm
    if inside.all() or not inside.any():
        return tangent[inside]
    i = int(np.argmin(inside))  # the first point past the stall torque
    s = (stall_torque_Nm - torque[i - 1]) / (torque[i] - torque[i - 1])
    return np.append(tangent[inside], tangent[i - 1] + s * (tangent[i] - tangent[i - 1]))


def working_range(t: pd.DataFrame, study: Study) -> pd.DataFrame:
    """Each solved row's smallest and largest tangent stiffness (Nm/rad) over the working range, the natural
    frequency (Hz) of the knee's inertia on the smallest, and the torque one sensor count stands for (Nm)."""
    stall, inertia = study.load_cases.stall_torque_Nm, study.ranking.knee_inertia_kg_m2
    tangents = [working_tangents(r, stall) if ok else np.array([]) for ok, (_, r) in zip(t["status"] == "ok", t.iterrows())]
    lo = pd.Series([x.min() if len(x) else np.nan for x in tangents], index=t.index)
    hi = pd.Series([x.max() if len(x) else np.nan for x in tangents], index=t.index)
    return pd.DataFrame({"working_min_tangent_k_Nm_per_rad": lo, "working_max_tangent_k_Nm_per_rad": hi,
                         "natural_frequency_Hz": np.sqrt(lo.clip(lower=0.0) / inertia) / (2 * math.pi),
                         "torque_per_count_Nm": hi * RAD_PER_COUNT})


def _strike_margin(t: pd.DataFrame, limit_Nm: float) -> pd.Series:
    strike, stop = _col(t, PROTECTION), _col(t, "large_stop_torque_Nm")
    stored = _col(t, "large_stop_energy_J") / _col(t, "strike_energy_J") - 1.0
    short = np.minimum(1.0 - stop / limit_Nm, stored)
    return (1.0 - strike / limit_Nm).where(strike.notna(), short)


def margins(t: pd.DataFrame, study: Study) -> pd.DataFrame:
    """One margin column per requirement (`requirement_list`) for every row; NaN where not solved or not
    judged. `t` has the physical columns (`physical.physical_columns`)."""
    req, lc = study.requirements, study.load_cases
    solved = t["status"] == "ok"
    out = pd.DataFrame(index=t.index)
    torques = {"stall": lc.stall_torque_Nm, "impact": lc.impact_torque_Nm}
    strain = {}
    for load in req.loads:
        out[f"{load}_travel_margin"], strain[load] = _load_margins(t, load, torques[load])
    for load in req.loads:
        out[f"{load}_strain_margin"] = strain[load]
    travel = _col(t, "large_stop_torque_Nm")
    if req.max_standing_deflection_deg is not None:
        sag = _col(t, "standing_deflection_deg")
        out["standing_margin"] = (1.0 - sag / req.max_standing_deflection_deg).where(
            sag.notna(), travel / study.robot.standing_knee_torque_Nm - 1.0)
    if req.max_stall_foot_error_mm is not None:
        error = _col(t, "stall_foot_error_mm")
        out["foot_error_margin"] = (1.0 - error / req.max_stall_foot_error_mm).where(
            error.notna(), travel / lc.stall_torque_Nm - 1.0)
    if req.max_torque_per_count_Nm is not None:
        out["torque_resolution_margin"] = 1.0 - _col(t, "torque_per_count_Nm") / req.max_torque_per_count_Nm
    if req.min_natural_frequency_Hz is not None:
        out["natural_frequency_margin"] = _col(t, "natural_frequency_Hz") / req.min_natural_frequency_Hz - 1.0
    if req.max_strike_torque_Nm is not None:
        out["strike_margin"] = _strike_margin(t, req.max_strike_torque_Nm)
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


def strain_use(t: pd.DataFrame, study: Study) -> pd.Series:
    """The largest share of its class's strain limit a required load's tensile strain uses (NaN where a
    limit is not sourced or a load not carried): the `strain_margin` objective, minimised."""
    shares = [tensile_strain(t, load) / _col(t, f"large_{load}_strain_limit")
              for load in study.requirements.loads]
    return pd.concat(shares, axis=1).max(axis=1, skipna=False) if shares else pd.Series(np.nan, index=t.index)


def lacks_limit(material: Material, load: str) -> bool:
    """Whether the material file sources no strain limit for the load's class (cyclic, or single-event)."""
    return (material.cyclic_strain_limit if LOAD_CLASS[load][0] == "cyclic" else material.elongation_at_yield) is None


def not_judged(t: pd.DataFrame, study: Study) -> pd.Series:
    """Per row, the requirements that cannot be judged for lack of a sourced material datum, each with the value
    the datum must reach for the design to pass: "passes if Cheetah's elongation at yield is at least 63.6 %"."""
    sf = study.ranking.safety_factor
    strains = {load: tensile_strain(t, load) for load in study.requirements.loads}
    out = []
    for i, row in t.iterrows():
        needs = []
        if row["status"] == "ok":
            material = study.candidate_of_row(row).material
            for load, strain in ((load, float(s[i])) for load, s in strains.items()):
                if not lacks_limit(material, load) or math.isnan(strain):
                    continue
                kind, datum = LOAD_CLASS[load]
                needed = strain * (sf if kind == "single" else 1.0)
                needs.append(f"{load} strain: passes if {material.name}'s {datum} is at least {100 * needed:.3g} %")
        out.append("; ".join(needs))
    return pd.Series(out, index=t.index, dtype=object)


# the margins of the requirements that bound the stiffness (the k window), with their words
WINDOW_MARGINS = ("standing_margin", "foot_error_margin", "natural_frequency_margin", "k_min_margin",
                  "torque_resolution_margin", "strike_margin", "k_max_margin")


def window_verdict(t: pd.DataFrame, index, study: Study) -> str:
    """Which of the window's requirements binds at design `index` (the smallest margin), and a finding when the
    window's requirements conflict on the computed curves: each is met by some solved design, none meets all."""
    words = {r.column: r.words for r in requirement_list(study) if r.column in WINDOW_MARGINS}
    if not words:
        return ""
    row = t.loc[index, list(words)].astype(float)
    text = ""
    if row.notna().any():
        c = row.idxmin()
        text = (f"At {t.loc[index, 'candidate']} the window's binding requirement is {words[c]}: "
                f"{'met with' if row[c] >= 0 else 'missed by'} {100 * abs(row[c]):.3g} % "
                f"{'to spare' if row[c] >= 0 else ''}".rstrip() + ".")
    met = t.loc[t["status"] == "ok", list(words)].astype(float) >= 0
    if len(met) and met.any().all() and not met.all(axis=1).any():
        text += (" Finding: the window's requirements conflict on the computed curves: each is met by some solved "
                 "design, but none meets all of " + ", ".join(words.values()) + " together.")
    return text


def envelope(t: pd.DataFrame, study: Study) -> pd.DataFrame:
    """Outer diameter and axial thickness (mm) of each row's design."""
    params = [study.candidate_of_row(r).params for _, r in t.iterrows()]
    return pd.DataFrame({"outer_diameter_mm": [2 * p.ring_outer_radius_mm for p in params],
                         "axial_thickness_mm": [p.thickness_mm for p in params]}, index=t.index)


def total_violation(m: pd.DataFrame) -> pd.Series:
    """Sum of the fractions by which the requirements are missed (requirements not judged add nothing)."""
    return (-m).clip(lower=0.0).fillna(0.0).sum(axis=1)
