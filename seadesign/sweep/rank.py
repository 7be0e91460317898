"""Choose a candidate: hard constraints, physical objectives, Pareto front and weighted score.

Objectives (both minimised):
- accuracy: `stall_bearing_displacement_mm`, the bearing displacement under stall torque;
- gearbox protection: `impact_gearbox_torque_Nm`, the peak torque a foot strike drives into the
  gearbox. The leg (inertia J about the knee, angular speed w = v / lower_leg at touchdown) is
  stopped by the spring with the gearbox side held: J w^2 / 2 = tau^2 / (2 k), so
  tau_peak = w sqrt(k J). The energy the spring stores at the impact torque, tau^2 / (2 k), is
  reported beside it. A static reaction force cannot measure protection: in statics the whole
  applied torque reaches the motor whatever k is (the thesis's 149-150 N for every design);
  the thesis's reaction numbers are kept for comparison.

For a linear spring both objectives depend on k alone (displacement ~ 1/k, impact torque ~
sqrt(k)), so every feasible candidate with a distinct k lies on the Pareto front; the weighted
score (weights from the study, min-max normalised objectives) picks the point on it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pandas as pd

from seadesign.constants import THESIS_FEA_RESULTS
from seadesign.design.study import Study

ACCURACY = "stall_bearing_displacement_mm"
PROTECTION = "impact_gearbox_torque_Nm"


@dataclass(frozen=True)
class Choice:
    """The chosen candidate (row index into the ranked table) and why."""

    index: int | None  # None when no candidate has FEA results
    runner_up: int | None
    feasible: bool  # whether the chosen candidate meets every hard constraint
    explanation: str


def pareto_front(objectives: np.ndarray) -> np.ndarray:
    """Mask of the non-dominated rows of an (n, m) array, all objectives minimised."""
    obj = np.asarray(objectives, dtype=float)
    mask = np.ones(len(obj), dtype=bool)
    for i in range(len(obj)):
        dominated = np.all(obj <= obj[i], axis=1) & np.any(obj < obj[i], axis=1)
        mask[i] = not dominated.any()
    return mask


def physical_columns(table: pd.DataFrame, study: Study) -> pd.DataFrame:
    """Standing deflection, impact energy and gearbox impact torque, extrapolation flag, thesis numbers."""
    rk, robot = study.ranking, study.robot
    t = table.copy()
    k = t["k_Nm_per_rad"] if "k_Nm_per_rad" in t else pd.Series(np.nan, index=t.index)
    omega = rk.impact_speed_m_per_s / robot.lower_leg_m
    t["standing_knee_torque_Nm"] = robot.standing_knee_torque_Nm
    t["standing_deflection_deg"] = np.degrees(robot.standing_knee_torque_Nm / k)
    t["impact_energy_J"] = study.load_cases.impact_torque_Nm ** 2 / (2 * k)
    t["impact_gearbox_torque_Nm"] = omega * np.sqrt(k * rk.knee_inertia_kg_m2)
    rotations = t.reindex(columns=["stall_rotation_rad", "impact_rotation_rad"]).abs()
    t["max_rotation_rad"] = rotations.max(axis=1, skipna=True)
    t["extrapolation"] = t["max_rotation_rad"] > rk.small_deflection_limit_rad
    t["small_deflection_limit_rad"] = rk.small_deflection_limit_rad
    thesis = [_thesis_result(study, row) for _, row in t.iterrows()]
    t["thesis_reaction_N"] = [r for r, _ in thesis]
    t["thesis_displacement_mm"] = [d for _, d in thesis]
    return t


def _thesis_result(study: Study, row: pd.Series) -> tuple[float, float]:
    """The thesis's (reaction N, displacement mm) for the row's beam count and thickness, when it reports them."""
    p = study.candidate_of_row(row).params
    return THESIS_FEA_RESULTS.get((p.beam_count, p.beam_thickness_mm), (math.nan, math.nan))


def constraint_columns(t: pd.DataFrame, study: Study) -> pd.DataFrame:
    """One boolean column per hard constraint, `feasible`, and `failed_constraints` in words."""
    rk, m = study.ranking, study.material
    allowable_MPa = m.yield_strength_Pa / rk.safety_factor * 1e-6
    solved = t["status"] == "ok"
    col = t.reindex(columns=["stall_von_mises_max_MPa", "impact_von_mises_max_MPa"])
    checks = {
        "valid geometry": t["status"] != "invalid",
        "solved": t["status"] != "failed",
        f"stall stress < {allowable_MPa:.3g} MPa": solved & (col["stall_von_mises_max_MPa"] < allowable_MPa),
        f"impact stress < {allowable_MPa:.3g} MPa": solved & (col["impact_von_mises_max_MPa"] < allowable_MPa),
        f"standing deflection < {rk.max_standing_deflection_deg:g} deg":
            solved & (t["standing_deflection_deg"] < rk.max_standing_deflection_deg),
    }
    if rk.k_min_Nm_per_rad is not None:
        checks[f"k >= {rk.k_min_Nm_per_rad:g} Nm/rad"] = solved & (t["k_Nm_per_rad"] >= rk.k_min_Nm_per_rad)
    if rk.k_max_Nm_per_rad is not None:
        checks[f"k <= {rk.k_max_Nm_per_rad:g} Nm/rad"] = solved & (t["k_Nm_per_rad"] <= rk.k_max_Nm_per_rad)
    t = t.copy()
    t["allowable_stress_MPa"] = allowable_MPa
    gate = {"valid geometry": pd.Series(True, index=t.index), "solved": t["status"] != "invalid"}
    fails = pd.DataFrame({name: gate.get(name, solved) & ~ok.fillna(False).astype(bool) for name, ok in checks.items()})
    t["failed_constraints"] = ["; ".join(c for c in fails.columns if row[c]) for _, row in fails.iterrows()]
    t["n_failed_constraints"] = fails.sum(axis=1).astype(int)
    t["feasible"] = t["n_failed_constraints"] == 0
    return t


def _normalised(values: pd.Series) -> pd.Series:
    """1 for the best (smallest) value, 0 for the worst; 1 everywhere when all are equal."""
    lo, hi = values.min(), values.max()
    return pd.Series(1.0, index=values.index) if hi == lo else (hi - values) / (hi - lo)


def rank(table: pd.DataFrame, study: Study) -> tuple[pd.DataFrame, Choice]:
    """Add physical, constraint, Pareto and score columns and choose a candidate.

    The pool is the feasible candidates; when none is feasible, the solved candidates that fail
    the fewest constraints (the choice is then marked infeasible and says what it violates).
    """
    t = constraint_columns(physical_columns(table, study), study)
    rk = study.ranking
    solved = t["status"] == "ok"
    t["pareto"] = False
    t["accuracy_score"] = np.nan
    t["protection_score"] = np.nan
    t["score"] = np.nan
    t["rank"] = pd.array([pd.NA] * len(t), dtype="Int64")
    if not solved.any():
        return t, Choice(None, None, False, "No candidate was solved, so none can be chosen; see the reasons column.")
    feasible = t["feasible"]
    pool = feasible if feasible.any() else solved & (t["n_failed_constraints"] == t.loc[solved, "n_failed_constraints"].min())
    p = t[pool]
    t.loc[pool, "pareto"] = pareto_front(p[[ACCURACY, PROTECTION]].to_numpy())
    acc, prot = _normalised(p[ACCURACY]), _normalised(p[PROTECTION])
    w = rk.weight_accuracy + rk.weight_protection
    t.loc[pool, "accuracy_score"] = acc
    t.loc[pool, "protection_score"] = prot
    t.loc[pool, "score"] = (rk.weight_accuracy * acc + rk.weight_protection * prot) / w
    order = t[pool].sort_values(["score", ACCURACY], ascending=[False, True]).index
    t.loc[order, "rank"] = np.arange(1, len(order) + 1)
    best = int(order[0])
    second = int(order[1]) if len(order) > 1 else None
    return t, Choice(best, second, bool(feasible.any()), explain(t, best, second, bool(feasible.any())))


def explain(t: pd.DataFrame, best: int, second: int | None, feasible: bool) -> str:
    """Why the chosen candidate wins and what the runner-up trades, in words."""
    b = t.loc[best]
    text = (f"{b['candidate']} wins with score {b['score']:.2f} (accuracy {b['accuracy_score']:.2f}, protection "
            f"{b['protection_score']:.2f}): k = {b['k_Nm_per_rad']:.3g} Nm/rad, stall displacement "
            f"{b[ACCURACY]:.3g} mm at the bearing, {b[PROTECTION]:.3g} Nm peak impact torque into the gearbox.")
    if not feasible:
        text = (f"No candidate meets every hard constraint; the choice is among those failing the fewest "
                f"({int(b['n_failed_constraints'])}: {b['failed_constraints']}). ") + text
    if second is not None:
        r = t.loc[second]
        acc_word = "more accurate" if r[ACCURACY] < b[ACCURACY] else "less accurate"
        prot_word = "protects the gearbox better" if r[PROTECTION] < b[PROTECTION] else "protects the gearbox less"
        text += (f" The runner-up {r['candidate']} (score {r['score']:.2f}) is {acc_word} "
                 f"({r[ACCURACY]:.3g} mm) but {prot_word} ({r[PROTECTION]:.3g} Nm)."
                 if (r[ACCURACY] < b[ACCURACY]) != (r[PROTECTION] < b[PROTECTION]) else
                 f" The runner-up {r['candidate']} (score {r['score']:.2f}) is {acc_word} ({r[ACCURACY]:.3g} mm) "
                 f"and {prot_word} ({r[PROTECTION]:.3g} Nm).")
    if bool(b["extrapolation"]):
        text += (f" Its rotation under load ({b['max_rotation_rad']:.2f} rad) exceeds the small-deflection limit "
                 f"({b['small_deflection_limit_rad']:g} rad), so its linear results are an extrapolation.")
    return text


def standing_verdict(ranked: pd.DataFrame, candidate: str, study: Study) -> str:
    """Whether `candidate` carries the robot's standing load in `ranked` (deflection vs the limit, deg)."""
    row = ranked.loc[ranked["candidate"] == candidate].iloc[0]
    limit = study.ranking.max_standing_deflection_deg
    deg = float(row["standing_deflection_deg"])
    verdict = "carries" if deg < limit else "does NOT carry"
    return (f"{candidate}: k {row['k_Nm_per_rad']:.4g} Nm/rad, standing deflection {deg:.3g} deg under "
            f"{row['standing_knee_torque_Nm']:.3g} Nm (limit {limit:g} deg): {verdict} the standing load")


def calibration_summary(base: pd.DataFrame, base_choice: Choice, calibrated: pd.DataFrame, choice: Choice,
                        study: Study) -> str:
    """Lines comparing the choice before and after calibration, each judged with the calibrated material."""
    if base_choice.index is None or choice.index is None:
        return "calibration: no candidate was solved, nothing to compare"
    before, after = base.loc[base_choice.index, "candidate"], calibrated.loc[choice.index, "candidate"]
    lines = [f"calibration: choice {'unchanged' if before == after else 'changes'}: {before} -> {after}",
             "  uncalibrated choice, calibrated material: " + standing_verdict(calibrated, before, study)]
    if after != before:
        lines.append("  calibrated choice: " + standing_verdict(calibrated, after, study))
    if not choice.feasible:
        lines.append("  no candidate meets every constraint with the calibrated material; see the report")
    return "\n".join(lines)
