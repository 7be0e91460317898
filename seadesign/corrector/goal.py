"""The closed-loop goal, cell by cell: each trial (direction x speed) in each setting.

A candidate meets the goal in a cell when its mean |Hall error| is at least `GOAL_REDUCTION` below
the best baseline's (no correction, PI, k-based feed-forward) in that cell, its peak |Hall error| is
not above the best baseline peak there, and its run is neither unstable nor oscillating.
`gain` = 1 - candidate mean / best baseline mean (the share of the best baseline's error removed).
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from seadesign.corrector.closedloop import ClosedLoopRun, trial_label

GOAL_REDUCTION = 0.30
BASELINES = ("none", "pi", "feedforward")


def cell_rows(run: ClosedLoopRun, setting: str) -> list[dict]:
    """One row per trial: mean and peak |Hall error| (rad) over both knees."""
    err = np.abs(run.hall - run.target)
    return [{"candidate": run.name, "setting": setting, "trial": trial_label(t),
             "mean_abs_error_rad": float(np.nanmean(err[i])), "peak_abs_error_rad": float(np.nanmax(err[i])),
             "flagged": bool(run.unstable or run.oscillating)} for i, t in enumerate(run.trials)]


def goal_table(runs: dict[str, list[ClosedLoopRun]], candidate: str, baselines: tuple[str, ...] = BASELINES) -> pd.DataFrame:
    """Per setting and trial: the candidate against the best baseline. `runs`: setting -> runs of that setting."""
    rows = []
    for setting, setting_runs in runs.items():
        cells = pd.DataFrame([r for run in setting_runs for r in cell_rows(run, setting)])
        base = cells[cells.candidate.isin(baselines)].groupby("trial")
        best_mean, best_peak = base.mean_abs_error_rad.min(), base.peak_abs_error_rad.min()
        best_name = cells.loc[base.mean_abs_error_rad.idxmin(), "candidate"].set_axis(best_mean.index)
        cand = cells[cells.candidate == candidate].set_index("trial")
        for trial, row in cand.iterrows():
            gain = 1.0 - row.mean_abs_error_rad / best_mean[trial]
            rows.append({"setting": setting, "trial": trial, "mean_abs_error_rad": row.mean_abs_error_rad,
                         "best_baseline": best_name[trial], "best_baseline_mean_abs_error_rad": best_mean[trial],
                         "gain": gain, "peak_abs_error_rad": row.peak_abs_error_rad,
                         "best_baseline_peak_abs_error_rad": best_peak[trial], "flagged": row.flagged,
                         "meets_goal": bool(gain >= GOAL_REDUCTION and row.peak_abs_error_rad <= best_peak[trial]
                                            and not row.flagged)})
    return pd.DataFrame(rows)
