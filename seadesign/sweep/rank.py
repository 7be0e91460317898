"""Choose a candidate: requirements judged and met, the deciding objective, the Pareto front.

Everything is read from the large-deflection path (`large_` columns, `fea.large_deflection`), not
from the linear model, which is far outside its range at these loads; the linear results stay in
the table for comparison with the thesis.

Objectives (all minimised; `sweep/requirements.py: OBJECTIVE_COLUMNS`): mass; accuracy, the arc the bearing
circle turns through at the stall torque; gearbox protection, the peak torque a foot strike drives into the
gearbox; strain_margin, the largest share of a load's strain limit used; softest_k, the small-load k. The
first objective of `[requirements] objectives` decides among feasible designs, mass breaks ties. The physical
columns these read are `sweep.physical`'s.

Feasible: valid geometry, solved, and every requirement judged and met. A design that meets every judged
requirement but has some that cannot be judged (a strain limit the material file does not source) is
conditional: never the choice while a feasible one exists, and reported with the value each missing datum
must reach.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
import pandas as pd
from pymoo.util.nds.non_dominated_sorting import NonDominatedSorting

from seadesign.design.study import Study
from seadesign.sweep.physical import physical_columns
from seadesign.sweep.requirements import (OBJECTIVE_COLUMNS, OBJECTIVE_WORDS, USABLE, margins, not_judged,
                                          requirement_list, total_violation)


@dataclass(frozen=True)
class Choice:
    """The chosen candidate (row index into the ranked table) and why."""

    index: int | None  # None when no candidate has FEA results
    runner_up: int | None
    feasible: bool  # whether the chosen candidate meets every requirement, each judged
    explanation: str
    conditional: bool = False  # chosen among designs that meet every judged requirement, some not judged


def pareto_front(objectives: np.ndarray) -> np.ndarray:
    """Mask of the non-dominated rows of an (n, m) array, all objectives minimised (pymoo's non-dominated
    sorting, the one domination test of the sweep and the explorer: equal rows do not dominate each other)."""
    obj = np.asarray(objectives, dtype=float)
    mask = np.zeros(len(obj), dtype=bool)
    if len(obj):
        mask[NonDominatedSorting().do(obj, only_non_dominated_front=True)] = True
    return mask


def constraint_columns(t: pd.DataFrame, study: Study) -> pd.DataFrame:
    """The requirement margins (`sweep/requirements.py`), `total_violation`, `failed_constraints` in words,
    their count, `not_judged` (the missing data and the values that would pass), `feasible` (every requirement
    judged and met) and `conditional` (every judged requirement met, some not judged). An invalid design fails
    only "valid geometry", one that failed to solve only "solved"."""
    m = margins(t, study)
    fails = pd.DataFrame({"valid geometry": t["status"] == "invalid", "solved": t["status"] == "failed"})
    for r in requirement_list(study):
        fails[r.words] = m[r.column] < 0
    t = pd.concat([t.drop(columns=[c for c in m.columns if c in t]), m], axis=1)
    solved = t["status"] == "ok"
    t["total_violation"] = total_violation(m).where(solved, np.inf)
    t["failed_constraints"] = ["; ".join(c for c in fails.columns if row[c]) for _, row in fails.iterrows()]
    t["n_failed_constraints"] = fails.sum(axis=1).astype(int)
    t["not_judged"] = not_judged(t, study)
    unjudged = m.isna().any(axis=1) if len(m.columns) else pd.Series(False, index=t.index)
    t["feasible"] = solved & (t["n_failed_constraints"] == 0) & ~unjudged
    t["conditional"] = solved & (t["n_failed_constraints"] == 0) & unjudged
    return t


def rank(table: pd.DataFrame, study: Study) -> tuple[pd.DataFrame, Choice]:
    """Add physical, constraint and Pareto columns and choose a candidate.

    The pool is the feasible candidates; when none is, the conditional ones (every judged requirement met);
    when none is, the solved candidates that fail the fewest requirements, ordered by the least total miss
    (the choice is then marked infeasible and says what it misses). A feasible or conditional pool is ordered
    by the deciding objective (the first of `[requirements] objectives`), mass breaking ties; a design without
    that objective (its curve stops before the stall torque or before storing the strike's energy) comes
    after, by the usable torque. The Pareto front is over all objectives, among the pool's designs that have
    them all.
    """
    t = constraint_columns(physical_columns(table, study), study)
    solved = t["status"] == "ok"
    t["pareto"] = False
    t["rank"] = pd.array([pd.NA] * len(t), dtype="Int64")
    if not solved.any():
        return t, Choice(None, None, False, "No candidate was solved, so none can be chosen; see the reasons column.")
    feasible, conditional = t["feasible"], t["conditional"]
    pool = feasible if feasible.any() else conditional if conditional.any() else \
        solved & (t["n_failed_constraints"] == t.loc[solved, "n_failed_constraints"].min())
    columns = [OBJECTIVE_COLUMNS[o] for o in study.requirements.objectives]
    p = t[pool]
    complete = p[columns].notna().all(axis=1)
    if complete.any():
        t.loc[complete[complete].index, "pareto"] = pareto_front(p.loc[complete, columns].to_numpy(float))
    keys = [columns[0], "mass_g", USABLE] if pool is feasible or pool is conditional else \
        ["total_violation", columns[0], "mass_g"]  # nothing meets the judged requirements: the least miss first
    order = p.sort_values(keys, ascending=[True, True, keys[-1] != USABLE], na_position="last").index
    t.loc[order, "rank"] = np.arange(1, len(order) + 1)
    best = int(order[0])
    second = int(order[1]) if len(order) > 1 else None
    choice = Choice(best, second, bool(feasible.any()), "", bool(not feasible.any() and conditional.any()))
    return t, replace(choice, explanation=explain(t, choice, study))


def explain(t: pd.DataFrame, choice: Choice, study: Study) -> str:
    """Why the chosen candidate wins and what the runner-up trades, in words; for an infeasible choice, what
    blocks it, by how much, and what would unblock it."""
    chosen = t.loc[choice.index]
    objective = study.requirements.objectives[0]
    column = OBJECTIVE_COLUMNS[objective]

    def value(r: pd.Series) -> str:
        return f"{OBJECTIVE_WORDS[objective]} {r[column]:.4g}" if np.isfinite(r[column]) else \
            f"no {OBJECTIVE_WORDS[objective]} (its path stops at {r['large_stop_torque_Nm']:.3g} Nm: {r['large_stop_reason']})"

    facts = (f"small-load k {chosen['k_Nm_per_rad']:.3g} Nm/rad, working-range tangent "
             f"{chosen['working_min_tangent_k_Nm_per_rad']:.3g}-"
             f"{chosen['working_max_tangent_k_Nm_per_rad']:.3g} Nm/rad, "
             f"{chosen['mass_g']:.3g} g; its path ends at {chosen['large_stop_torque_Nm']:.3g} Nm, "
             f"{chosen['large_stop_rotation_rad']:.3g} rad ({chosen['large_stop_reason']})")
    if choice.feasible:
        text = f"{chosen['candidate']} meets every requirement and has the smallest {value(chosen)}: {facts}."
    elif choice.conditional:
        text = (f"No candidate meets every requirement with each judged. {chosen['candidate']} meets every requirement "
                f"that can be judged, with the smallest {value(chosen)}, but is only conditional: "
                f"{chosen['not_judged']}. "
                f"It is {facts}.")
    else:
        text = (f"No candidate meets every requirement: NOT a recommendation. The closest "
                f"({int(chosen['n_failed_constraints'])} "
                f"missed) is {chosen['candidate']}, which misses {blocking(chosen, study)}; {facts}.")
        if chosen["not_judged"]:
            text += f" Not judged: {chosen['not_judged']}."
        text += " " + unblock(chosen, study)
    if choice.runner_up is not None:
        r = t.loc[choice.runner_up]
        text += f" Runner-up: {r['candidate']}, {value(r)}" + ("." if not r["failed_constraints"] else
                                                                f", missing {r['failed_constraints']}.")
    return text


def blocking(row: pd.Series, study: Study) -> str:
    """The requirements a design misses, each with the fraction it misses by, the worst first."""
    missed = [(float(row[r.column]), r.words) for r in requirement_list(study)
              if np.isfinite(row.get(r.column, np.nan)) and row[r.column] < 0]
    return "; ".join(f"{words} (by {100 * -m:.3g} %)" for m, words in sorted(missed)) or "nothing judged"


def unblock(row: pd.Series, study: Study) -> str:
    """What would unblock a design that misses requirements, in words."""
    hints = []
    if any(row.get(f"{load}_travel_margin", 0.0) < 0 for load in study.requirements.loads):
        reason, cause = row["large_stop_reason"], row.get("large_unconverged_cause", "")
        if isinstance(cause, str) and cause:  # a row from an older table has none (or NaN)
            hints.append(f"its path ends unconverged in contact before a load ({cause.replace('_', ' ')} at "
                         f"{row['large_unconverged_rotation_rad']:.4g} rad, at x {row['large_unconverged_at_x_mm']:.1f}, "
                         f"y {row['large_unconverged_at_y_mm']:.1f} mm): a stiffer material or a larger envelope")
        else:
            ends = "unconverged" if reason == "unconverged" else f"in a {reason.replace('_', ' ')}"
            hints.append(f"its path ends {ends} before a load: a stiffer material or a larger envelope")
    if row.get("torque_resolution_margin", 0.0) < 0 or row.get("k_max_margin", 0.0) < 0:
        hints.append("a softer spring (thinner or fewer beams, a softer material)")
    if any(row.get(c, 0.0) < 0 for c in ("standing_margin", "natural_frequency_margin", "k_min_margin",
                                         "foot_error_margin")):
        hints.append("a stiffer spring (more or wider beams, a stiffer material)")
    if any(row.get(f"{load}_strain_margin", 0.0) < 0 for load in study.requirements.loads):
        hints.append("lower strain: longer beams, larger fillets, or a material with a higher sourced limit")
    if row.get("not_judged"):
        hints.append("a material with a sourced value for each missing datum")
    return ("What would unblock it: " + "; ".join(hints) + ".") if hints else ""
