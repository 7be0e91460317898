"""The explorer's loop: design of experiments, surrogates, search, verification, until the budget is
spent or the front stops moving.

1. The initial design (`doe.py`) is screened (cheap: geometry and validity); invalid designs are
   replaced from a space-filling pool, and the valid ones are evaluated on the full pipeline.
2. Each round fits the surrogates on everything verified (`models.py`), searches them (`search.py`)
   for a batch of designs, screens those, and evaluates the valid ones. A proposal that screens invalid
   is replaced by the search's spares, screened in order, until the batch is full or SPARES_PER_DESIGN x the
   batch spares are spent: the batch's designs are evaluated in parallel, and a round that verified fewer
   would leave workers idle. Designs are only ever reported from these evaluations: a surrogate steers, it
   never decides.
3. Stop rule: the budget of full evaluations is spent; or `patience` rounds in a row have not moved
   the front: no newly verified design entered the verified front (a design meeting every judged requirement
   that no earlier such design dominates: the search models what can be judged, so where a requirement cannot
   be judged anywhere it finds the best conditional design), or, while no design is feasible, none lowered the least total
   violation by 1 % of it or more; or the search proposes nothing that was not screened before; or the
   screening budget (`screen_factor` x the budget) is spent. A round whose proposals and spares all screen
   invalid teaches the classifier and does not count as a round of the front.
Everything is seeded: the same problem, budget and seed give the same designs, so an interrupted
run resumes by running again (evaluations come back from the problem's own store).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from threadpoolctl import threadpool_limits

from seadesign.explore.doe import initial_design, initial_size, pool, unique_rows
from seadesign.explore.models import Models, fit_models
from seadesign.explore.problem import (FEASIBLE, MEETS_JUDGED, SOLVED, TOTAL_VIOLATION, VALID, Problem, best_index,
                                       front_mask, judge)
from seadesign.explore.search import far_from, propose

SURROGATE_THREADS = 1  # BLAS threads while fitting and searching the surrogates: their matrices are small, and
# more threads made a round slower on busy cores (docs/validation/timing.md)
SPARES_PER_DESIGN = 2  # replacements the search offers per design of the batch, for proposals that screen invalid
VIOLATION_PROGRESS = 0.01  # a round that lowers the least total violation by less than this fraction does not count


@dataclass(frozen=True)
class LoopSettings:
    budget: int  # full evaluations at most
    batch: int = 2  # designs verified per round (evaluated in parallel)
    initial: int | None = None  # designs in the initial sample (default `doe.initial_size`)
    patience: int = 2  # rounds without a move of the front before stopping
    seed: int = 0
    screen_factor: int = 5  # screenings at most this many times the budget


@dataclass(frozen=True)
class Round:
    """The state after one round (round 0: the initial design)."""

    index: int
    evaluations: int  # full evaluations so far
    screenings: int  # cheap screenings so far
    best_objective: float  # first objective of the best design meeting every judged requirement (NaN: none)
    least_violation: float  # least total violation of a solved design
    front_size: int
    moved: bool


@dataclass
class Exploration:
    """What an exploration verified and how it went."""

    evaluated: pd.DataFrame  # one row per full evaluation: x0.., the problem's columns, TOTAL_VIOLATION, FEASIBLE,
    # `front`, `round`
    screened: pd.DataFrame  # one row per screening: x0.., VALID, the screened columns, `round`
    rounds: list[Round] = field(default_factory=list)
    stop_reason: str = ""
    models: Models | None = None  # fitted on everything verified, at the end
    best: int | None = None  # row of `evaluated` chosen (`problem.best_index`); None when nothing was solved


def _xframe(X: np.ndarray) -> pd.DataFrame:
    return pd.DataFrame(X, columns=[f"x{i}" for i in range(X.shape[1])])


class _State:
    """The growing tables of one run."""

    def __init__(self, problem: Problem, settings: LoopSettings) -> None:
        self.problem, self.settings = problem, settings
        d = problem.encoding.dim
        self.evaluated = pd.DataFrame(columns=[f"x{i}" for i in range(d)])
        self.screened = pd.DataFrame(columns=[f"x{i}" for i in range(d)])

    def X(self, table: pd.DataFrame) -> np.ndarray:
        return table[[f"x{i}" for i in range(self.problem.encoding.dim)]].to_numpy(float).reshape(
            len(table), self.problem.encoding.dim)

    @property
    def screens_left(self) -> int:
        return self.settings.screen_factor * self.settings.budget - len(self.screened)

    @property
    def evaluations_left(self) -> int:
        return self.settings.budget - len(self.evaluated)

    def screen(self, X: np.ndarray, round_index: int) -> np.ndarray:
        """Screen the designs not screened before; returns the valid ones among X (in order, no repeats)."""
        X = unique_rows(X)
        fresh = X[far_from(self.X(self.screened), X)][: max(self.screens_left, 0)]
        if len(fresh):
            rows = pd.concat([_xframe(fresh), self.problem.screen(fresh).reset_index(drop=True)], axis=1)
            rows["round"] = round_index
            self.screened = pd.concat([self.screened, rows], ignore_index=True) if len(self.screened) else rows
        valid = self.screened[self.screened[VALID].astype(bool)]
        return X[~far_from(self.X(valid), X)]

    def evaluate(self, X: np.ndarray, round_index: int) -> int:
        X = unique_rows(X)
        X = X[far_from(self.X(self.evaluated), X)][: self.evaluations_left]
        if not len(X):
            return 0
        rows = pd.concat([_xframe(X), self.problem.evaluate(X).reset_index(drop=True)], axis=1)
        rows["round"] = round_index
        self.evaluated = judge(pd.concat([self.evaluated, rows], ignore_index=True) if len(self.evaluated) else rows,
                               self.problem)
        failed = self.X(rows[~rows[SOLVED].astype(bool)])
        if len(failed):  # a design the pipeline cannot solve is learned as not buildable
            hit = ~far_from(failed, self.X(self.screened))
            self.screened.loc[hit, VALID] = False
        return len(X)


def _summary(state: _State, index: int, moved: bool) -> Round:
    t, objectives = state.evaluated, state.problem.objectives
    feasible = t[t[MEETS_JUDGED]] if len(t) else t
    solved = t[t[SOLVED].astype(bool)] if len(t) else t
    return Round(index, len(t), len(state.screened),
                 float(feasible[objectives[0]].min()) if len(feasible) else math.nan,
                 float(solved[TOTAL_VIOLATION].min()) if len(solved) else math.nan,
                 int(front_mask(t, objectives, MEETS_JUDGED).sum()) if len(t) else 0, moved)


def _moved(before: pd.DataFrame, after: pd.DataFrame, objectives: tuple[str, ...]) -> bool:
    """Whether the designs added since `before` moved the front (see the module doc)."""
    new = after.iloc[len(before):]
    old_feasible = before[before[MEETS_JUDGED]] if len(before) else before
    for _, r in new[new[MEETS_JUDGED]].iterrows():
        f = r[list(objectives)].to_numpy(float)
        if not np.isfinite(f).all():
            continue
        F = old_feasible[list(objectives)].to_numpy(float) if len(old_feasible) else np.empty((0, len(objectives)))
        if not (np.all(F <= f, axis=1) & np.any(F < f, axis=1)).any():
            return True
    if len(old_feasible) or after[MEETS_JUDGED].any():
        return False
    old = before[TOTAL_VIOLATION].min() if len(before) else math.inf
    return bool(after[TOTAL_VIOLATION].min() < old * (1 - VIOLATION_PROGRESS))


def explore(problem: Problem, settings: LoopSettings, jobs: int = 1) -> Exploration:
    """Run the loop (see the module doc) and return every verified design, the rounds and the final models;
    `jobs` processes fit the surrogates (the same models as one)."""
    if settings.budget < 2:
        raise ValueError(f"the budget must allow at least 2 full evaluations (got {settings.budget})")
    state = _State(problem, settings)
    enc = problem.encoding
    n0 = settings.initial or initial_size(enc.dim, settings.budget)
    X0 = state.screen(initial_design(enc, n0, settings.seed), 0)
    spare = pool(enc, 8 * n0, settings.seed + 1)
    spare = spare[far_from(state.X(state.screened), spare)]  # designs not screened yet
    while len(X0) < n0 and state.screens_left > 0 and len(spare):
        take, spare = spare[: n0 - len(X0)], spare[n0 - len(X0):]
        X0 = np.vstack([X0, state.screen(take, 0)])
    state.evaluate(X0[:n0], 0)
    rounds = [_summary(state, 0, True)]
    stop, still = "budget spent", 0
    index = 0
    while state.evaluations_left > 0:
        index += 1
        verified_F = state.evaluated[list(problem.objectives)].to_numpy(float).copy()
        verified_F[~state.evaluated[MEETS_JUDGED].to_numpy(bool)] = np.nan
        want = min(settings.batch, state.evaluations_left)
        with threadpool_limits(SURROGATE_THREADS):
            models = fit_models(problem, state.evaluated, state.screened, settings.seed, jobs, SURROGATE_THREADS)
            X = propose(enc, models, want, state.X(state.screened), verified_F, settings.seed + index,
                        SPARES_PER_DESIGN * want)
        if not len(X):
            stop = "the search proposed no design that was not screened before"
            break
        before = state.evaluated.copy()
        valid = np.empty((0, enc.dim))
        while len(valid) < want and len(X) and state.screens_left > 0:  # the batch, then spares for invalid ones
            missing = want - len(valid)
            valid, X = np.vstack([valid, state.screen(X[:missing], index)]), X[missing:]
        if not len(valid):  # every proposal and spare was invalid: the classifier learns; not a round of the front
            if state.screens_left <= 0:
                stop = "the screening budget is spent"
                break
            continue
        state.evaluate(valid, index)
        moved = _moved(before, state.evaluated, problem.objectives)
        rounds.append(_summary(state, index, moved))
        still = 0 if moved else still + 1
        if still >= settings.patience:
            stop = f"the front did not move in {settings.patience} rounds"
            break
    t = state.evaluated.copy()
    t["front"] = front_mask(t, problem.objectives, FEASIBLE if t[FEASIBLE].any() else MEETS_JUDGED)
    best = best_index(t, problem.objectives)
    with threadpool_limits(SURROGATE_THREADS):
        models = fit_models(problem, state.evaluated, state.screened, settings.seed, jobs, SURROGATE_THREADS)
    return Exploration(t, state.screened, rounds, stop, models, None if best is None else int(best))
