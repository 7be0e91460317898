"""What the explorer explores: a design space, a cheap screen, an expensive evaluation, and how
their columns are read (objectives, requirement margins, outputs).

A problem evaluates a batch of unit-cube designs (`encoding.py`) and returns one row per design.
Margins are relative: >= 0 is met (by that fraction), < 0 missed (by that fraction), NaN cannot be
judged (the requirement is then reported as not judged, never as met). The knee's problem is
`spring_problem.SpringProblem`; the analytic test problems implement the same protocol.
"""

from __future__ import annotations

from typing import Protocol

import numpy as np
import pandas as pd

from seadesign.explore.encoding import Encoding
from seadesign.sweep.rank import pareto_front
from seadesign.sweep.requirements import total_violation

SOLVED = "solved"  # evaluation column: the full pipeline gave results
VALID = "valid"  # screening column: the geometry can be built and printed
TOTAL_VIOLATION = "total_violation"  # sum over requirements of the fraction each is missed by (0: feasible)
FEASIBLE = "feasible"  # solved, every requirement judged and met
CONDITIONAL = "conditional"  # optional column: every judged requirement met, some not judged (not feasible)
MEETS_JUDGED = "meets_judged"  # feasible or conditional: what the search steers by (it models what can be judged)


class DesignProblem(Protocol):
    encoding: Encoding
    objectives: tuple[str, ...]  # columns minimised; the first decides the choice among feasible designs
    margins: tuple[str, ...]  # requirement margins (relative, >= 0 met)
    outputs: tuple[str, ...]  # physical outputs with a surrogate (leave-one-out error, sensitivity)
    screened: tuple[str, ...]  # columns the cheap screen gives exactly (their surrogates also learn from it)

    def screen(self, X: np.ndarray) -> pd.DataFrame:
        """One row per design: VALID and the `screened` columns (cheap)."""

    def evaluate(self, X: np.ndarray) -> pd.DataFrame:
        """One row per design: SOLVED and the objective, margin and output columns (the full pipeline)."""

    # optional: unjudged(column, X) -> bool mask of the designs where a margin cannot be judged


def judge(rows: pd.DataFrame, problem: DesignProblem) -> pd.DataFrame:
    """Rows with TOTAL_VIOLATION (inf where not solved), MEETS_JUDGED (solved, no judged requirement missed) and
    FEASIBLE (that, and not conditional where the problem marks designs whose requirements are not all judged)."""
    t = rows.copy()
    solved = t[SOLVED].astype(bool)
    t[TOTAL_VIOLATION] = np.where(solved, total_violation(t[list(problem.margins)]), np.inf)
    t[MEETS_JUDGED] = solved & (t[TOTAL_VIOLATION] == 0.0)
    t[FEASIBLE] = t[MEETS_JUDGED] & ~t[CONDITIONAL].astype(bool) if CONDITIONAL in t else t[MEETS_JUDGED]
    return t


def front_mask(t: pd.DataFrame, objectives: tuple[str, ...], column: str = FEASIBLE) -> pd.Series:
    """The designs of `column` (feasible by default) no other such design dominates (objectives minimised)."""
    pool = t[column] & t[list(objectives)].notna().all(axis=1)
    mask = pd.Series(False, index=t.index)
    if pool.any():
        mask[pool] = pareto_front(t.loc[pool, list(objectives)].to_numpy(float))
    return mask


def best_index(t: pd.DataFrame, objectives: tuple[str, ...]):
    """The choice: the feasible design with the smallest first objective; with none feasible, the conditional
    one (when the problem marks them); with none, the solved design that misses its requirements by the least
    in total (None when nothing was solved)."""
    for column in (FEASIBLE, CONDITIONAL):
        pool = t[t[column].astype(bool) & t[objectives[0]].notna()] if column in t else t.iloc[:0]
        if len(pool):
            return pool[objectives[0]].idxmin()
    solved = t[t[SOLVED].astype(bool)]
    return solved[TOTAL_VIOLATION].idxmin() if len(solved) else None
