"""Choose a candidate: hard constraints, physical objectives, Pareto front and weighted score.

Everything is read from the large-deflection path (`large_` columns, `fea.large_deflection`), not
from the linear model, which is far outside its range at these loads; the linear results stay in
the table for comparison with the thesis.

Objectives (both minimised):
- accuracy: `large_stall_bearing_displacement_mm`, the arc the bearing circle turns through at the
  stall torque;
- gearbox protection: `impact_gearbox_torque_Nm`, the peak torque a foot strike drives into the
  gearbox. The leg (inertia J about the knee, angular speed w = v / lower_leg at touchdown) is
  stopped by the spring with the gearbox side held: its kinetic energy J w^2 / 2 goes into the
  spring, int_0^theta T dtheta, and the torque where the curve has stored it is the peak. (A linear
  spring gives tau_peak = w sqrt(k J).) A curve that ends before it has stored that energy gives
  no number: the strike reaches the path's stop. A static reaction force cannot measure protection:
  in statics the whole applied torque reaches the motor whatever k is (the thesis's 149-150 N for
  every design).

Hard constraints: valid geometry; solved; the path carries the stall and the impact torque (a stop
before it, contact unless the study makes contact an end stop, a limit point or a buckling mode, fails
the load); the peak strain at each load within the allowable strain (elongation at yield / safety
factor); the standing deflection read from the curve; the study's k range (small-load k).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pandas as pd

from seadesign.constants import THESIS_FEA_RESULTS
from seadesign.design.spring import TorqueCurve
from seadesign.design.study import Study
from seadesign.sweep.handoff import curve_to_stop
# USABLE orders a pool that no objective can rank: the most usable torque first
from seadesign.sweep.requirements import ACCURACY, PROTECTION, USABLE, margins, requirement_list, total_violation


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


def strike_torque(row: pd.Series, energy_J: float) -> float:
    """The torque (Nm) where the row's curve, up to where its path stops, has stored `energy_J` (J); NaN when
    it stores less."""
    torque = TorqueCurve(*map(tuple, curve_to_stop(row))).torque_at_energy(energy_J)
    return math.nan if torque is None else torque


def physical_columns(table: pd.DataFrame, study: Study) -> pd.DataFrame:
    """Standing deflection, impact energy and gearbox strike torque read from each curve, the usable torque
    (the smaller of where the path stops and where the peak strain passes the allowable), thesis numbers."""
    rk, robot = study.ranking, study.robot
    t = table.copy()
    energy = 0.5 * rk.knee_inertia_kg_m2 * (rk.impact_speed_m_per_s / robot.lower_leg_m) ** 2
    solved = t["status"] == "ok"
    t["standing_knee_torque_Nm"] = robot.standing_knee_torque_Nm
    t["standing_deflection_deg"] = np.degrees(t["large_standing_rotation_rad"]) if "large_standing_rotation_rad" in t \
        else np.nan
    t["strike_energy_J"] = energy
    if "large_stop_torque_Nm" in t:
        t[USABLE] = t[["large_stop_torque_Nm", "large_strain_limit_torque_Nm"]].min(axis=1, skipna=True)
    t[PROTECTION] = [strike_torque(r, energy) if ok else np.nan for ok, (_, r) in zip(solved, t.iterrows())]
    thesis = [_thesis_result(study, row) for _, row in t.iterrows()]
    t["thesis_reaction_N"] = [r for r, _ in thesis]
    t["thesis_displacement_mm"] = [d for _, d in thesis]
    return t


def _thesis_result(study: Study, row: pd.Series) -> tuple[float, float]:
    """The thesis's (reaction N, displacement mm) for the row's beam count and thickness, when it reports them."""
    p = study.candidate_of_row(row).params
    return THESIS_FEA_RESULTS.get((p.beam_count, p.beam_thickness_mm), (math.nan, math.nan))


def constraint_columns(t: pd.DataFrame, study: Study) -> pd.DataFrame:
    """The requirement margins (`sweep/requirements.py`), `total_violation`, `failed_constraints` in words,
    their count and `feasible`. An invalid design fails only "valid geometry", one that failed to solve only
    "solved"; a requirement that cannot be judged is not counted as failed."""
    m = margins(t, study)
    fails = pd.DataFrame({"valid geometry": t["status"] == "invalid", "solved": t["status"] == "failed"})
    for r in requirement_list(study):
        fails[r.words] = m[r.column] < 0
    t = pd.concat([t.drop(columns=[c for c in m.columns if c in t]), m], axis=1)
    t["total_violation"] = total_violation(m).where(t["status"] == "ok", np.inf)
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

    The pool is the feasible candidates; when none is feasible, the solved candidates that fail the
    fewest constraints (the choice is then marked infeasible and says what it violates). A pool in which
    some candidate has no objective (its curve stops before the stall torque or before storing the
    strike's energy) cannot be scored: it is ordered by the usable torque, the most a candidate carries
    before its path stops and within the allowable strain.
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
    scored = bool(p[[ACCURACY, PROTECTION]].notna().all(axis=None))
    if scored:
        t.loc[pool, "pareto"] = pareto_front(p[[ACCURACY, PROTECTION]].to_numpy())
        acc, prot = _normalised(p[ACCURACY]), _normalised(p[PROTECTION])
        w = rk.weight_accuracy + rk.weight_protection
        t.loc[pool, "accuracy_score"] = acc
        t.loc[pool, "protection_score"] = prot
        t.loc[pool, "score"] = (rk.weight_accuracy * acc + rk.weight_protection * prot) / w
        order = t[pool].sort_values(["score", ACCURACY], ascending=[False, True]).index
    else:
        order = t[pool].sort_values([USABLE, "k_Nm_per_rad"], ascending=[False, True]).index
    t.loc[order, "rank"] = np.arange(1, len(order) + 1)
    best = int(order[0])
    second = int(order[1]) if len(order) > 1 else None
    explanation = explain(t, best, second, bool(feasible.any())) if scored else _explain_carried(t, best, second)
    return t, Choice(best, second, bool(feasible.any()), explanation)


def _explain_carried(t: pd.DataFrame, best: int, second: int | None) -> str:
    """Why a pool without objectives chose `best`: the most usable torque."""
    b = t.loc[best]

    def usable(r: pd.Series) -> str:
        limit = r["large_strain_limit_torque_Nm"]
        strain = f", the allowable strain passed at {limit:.3g} Nm" if np.isfinite(limit) else ""
        return (f"{r[USABLE]:.3g} Nm usable (its path stops at {r['large_stop_torque_Nm']:.3g} Nm, "
                f"{r['large_stop_rotation_rad']:.3g} rad: {r['large_stop_reason']}{strain})")

    text = (f"No candidate meets every hard constraint, and the ones failing the fewest "
            f"({int(b['n_failed_constraints'])}: {b['failed_constraints']}) cannot all be scored, so the choice is "
            f"the one with the most usable torque, the most it carries before its path stops and within the "
            f"allowable strain: {b['candidate']}, {usable(b)}; small-load k {b['k_Nm_per_rad']:.3g} Nm/rad.")
    if second is not None:
        text += f" Next: {t.loc[second, 'candidate']}, {usable(t.loc[second])}."
    return text


def explain(t: pd.DataFrame, best: int, second: int | None, feasible: bool) -> str:
    """Why the chosen candidate wins and what the runner-up trades, in words."""
    b = t.loc[best]
    text = (f"{b['candidate']} wins with score {b['score']:.2f} (accuracy {b['accuracy_score']:.2f}, protection "
            f"{b['protection_score']:.2f}): {b['large_stall_rotation_rad']:.3g} rad at the stall torque "
            f"(secant k {b['large_stall_secant_k_Nm_per_rad']:.3g} Nm/rad, small-load k {b['k_Nm_per_rad']:.3g}), "
            f"{b[ACCURACY]:.3g} mm at the bearing, {b[PROTECTION]:.3g} Nm peak strike torque into the gearbox.")
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
    return text


def standing_verdict(ranked: pd.DataFrame, candidate: str, study: Study) -> str:
    """Whether `candidate` carries the robot's standing load in `ranked` (deflection vs the limit, deg)."""
    row = ranked.loc[ranked["candidate"] == candidate].iloc[0]
    limit = study.requirements.max_standing_deflection_deg
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
