"""The explorer, as ask and tell: design of experiments, surrogates, search, verification, until a stop rule
fires. `Explorer.ask` gives the designs to evaluate next, `Explorer.tell` takes the problem's rows for them;
`explore` runs the two until the stop.

1. The initial design (`doe.py`) is screened (cheap: geometry and validity); invalid designs are
   replaced from a space-filling pool, and the valid ones are evaluated on the full pipeline.
2. Each round fits the surrogates on everything verified (`models.py`), searches them (`search.py`)
   for a batch of designs, screens those, and evaluates the valid ones. A proposal that screens invalid
   is replaced by the search's spares, screened in order, until the batch is full or SPARES_PER_DESIGN x the
   batch spares are spent: the batch's designs are evaluated in parallel, and a round that verified fewer
   would leave workers idle. Designs are only ever reported from these evaluations: a surrogate steers, it
   never decides.
3. Stop rules (`stopping.py`, read after each round in this order): `patience` rounds in a row have not moved
   the front: no newly verified design entered the verified front (a design meeting every judged requirement
   that no earlier such design dominates: the search models what can be judged, so where a requirement cannot
   be judged anywhere it finds the best conditional design), or, while no design is feasible, none lowered the
   least total violation by 1 % of it or more; a round whose proposals and spares all screen invalid when the
   screening budget (`screen_factor` x the budget) is spent; the budget of full evaluations is spent. The search
   proposing nothing that was not screened before also stops it. A round whose proposals and spares all screen
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
from seadesign.explore.problem import (FEASIBLE, MEETS_JUDGED, SOLVED, TOTAL_VIOLATION, VALID, DesignProblem,
                                       best_index, front_mask, judge)
from seadesign.explore.search import far_from, propose
from seadesign.explore.stopping import EvaluationBudget, Progress, ScreeningBudget, StalledFront, StopRule, first_reason
from seadesign.sweep.rank import pareto_front

SURROGATE_THREADS = 1  # BLAS threads while fitting and searching the surrogates: their matrices are small, and
# more threads made a round slower on busy cores (docs/validation/timing.md)
SPARES_PER_DESIGN = 2  # replacements the search offers per design of the batch, for proposals that screen invalid
VIOLATION_PROGRESS = 0.01  # a round that lowers the least total violation by less than this fraction does not count


@dataclass(frozen=True)
class ExplorerSettings:
    budget: int  # full evaluations at most
    batch: int = 2  # designs verified per round (evaluated in parallel)
    initial: int | None = None  # designs in the initial sample (default `doe.initial_size`)
    patience: int = 2  # rounds without a move of the front before stopping
    seed: int = 0
    screen_factor: int = 5  # screenings at most this many times the budget

    def stop_rules(self) -> tuple[StopRule, ...]:
        """The stop rules these settings give, in the order they are read (see the module doc)."""
        return (StalledFront(self.patience), ScreeningBudget(self.screen_factor * self.budget),
                EvaluationBudget(self.budget))


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

    def __init__(self, problem: DesignProblem, settings: ExplorerSettings) -> None:
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

    def admit(self, X: np.ndarray) -> np.ndarray:
        """The designs of X to evaluate: no repeats, none evaluated before, within the budget."""
        X = unique_rows(X)
        return X[far_from(self.X(self.evaluated), X)][: self.evaluations_left]

    def add(self, X: np.ndarray, rows: pd.DataFrame, round_index: int) -> None:
        """Record the problem's rows for the admitted designs X; a design that failed to solve is learned as not
        buildable."""
        rows = pd.concat([_xframe(X), rows.reset_index(drop=True)], axis=1)
        rows["round"] = round_index
        self.evaluated = judge(pd.concat([self.evaluated, rows], ignore_index=True) if len(self.evaluated) else rows,
                               self.problem)
        failed = self.X(rows[~rows[SOLVED].astype(bool)])
        if len(failed):
            hit = ~far_from(failed, self.X(self.screened))
            self.screened.loc[hit, VALID] = False


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
    F = old_feasible[list(objectives)].to_numpy(float) if len(old_feasible) else np.empty((0, len(objectives)))
    for _, r in new[new[MEETS_JUDGED]].iterrows():
        f = r[list(objectives)].to_numpy(float)
        if np.isfinite(f).all() and pareto_front(np.vstack([F, f]))[-1]:  # no earlier such design dominates it
            return True
    if len(old_feasible) or after[MEETS_JUDGED].any():
        return False
    old = before[TOTAL_VIOLATION].min() if len(before) else math.inf
    return bool(after[TOTAL_VIOLATION].min() < old * (1 - VIOLATION_PROGRESS))


class Explorer:
    """The explorer of one problem as ask and tell (see the module doc); `jobs` processes fit the surrogates
    (the same models as one), `rules` replace the settings' stop rules."""

    def __init__(self, problem: DesignProblem, settings: ExplorerSettings, jobs: int = 1,
                 rules: tuple[StopRule, ...] | None = None) -> None:
        if settings.budget < 2:
            raise ValueError(f"the budget must allow at least 2 full evaluations (got {settings.budget})")
        self.problem, self.settings, self.jobs = problem, settings, jobs
        self.rules = settings.stop_rules() if rules is None else rules
        self.state = _State(problem, settings)
        self.rounds: list[Round] = []
        self.round_index = 0  # the round asked last (0: the initial design)
        self.rounds_without_move = 0
        self.stop_reason: str | None = None

    def ask(self) -> np.ndarray | None:
        """The next designs to evaluate (unit cube, screened valid, none evaluated before; possibly none), or
        None once the exploration has stopped."""
        if self.stop_reason is not None:
            return None
        if not self.rounds:
            return self.state.admit(self._initial_design())
        while True:
            if self.state.evaluations_left <= 0:  # the settings' budget caps a caller's own rules too
                self.stop_reason = "budget spent"
                return None
            self.round_index += 1
            want = min(self.settings.batch, self.state.evaluations_left)
            X = self._propose(want)
            if not len(X):
                self.stop_reason = "the search proposed no design that was not screened before"
                return None
            valid = np.empty((0, self.problem.encoding.dim))
            while len(valid) < want and len(X) and self.state.screens_left > 0:  # the batch, then spares
                missing = want - len(valid)
                valid, X = np.vstack([valid, self.state.screen(X[:missing], self.round_index)]), X[missing:]
            if len(valid):
                return self.state.admit(valid)
            # every proposal and spare was invalid: the classifier learns; not a round of the front
            self.stop_reason = first_reason(self.rules, self._progress(empty_round=True))
            if self.stop_reason is not None:
                return None

    def tell(self, X: np.ndarray, rows: pd.DataFrame | None) -> None:
        """The problem's rows (`DesignProblem.evaluate`) for the designs X that `ask` gave (None when it gave
        none)."""
        before = self.state.evaluated.copy()
        if len(X):
            self.state.add(X, rows, self.round_index)
        moved = not self.rounds or _moved(before, self.state.evaluated, self.problem.objectives)
        self.rounds.append(_summary(self.state, self.round_index, moved))
        self.rounds_without_move = 0 if moved else self.rounds_without_move + 1
        self.stop_reason = first_reason(self.rules, self._progress(empty_round=False))

    def result(self) -> Exploration:
        """Every verified design with the verified front, the rounds, the stop and the models fitted on
        everything verified."""
        t = self.state.evaluated.copy()
        t["front"] = front_mask(t, self.problem.objectives, FEASIBLE if t[FEASIBLE].any() else MEETS_JUDGED)
        best = best_index(t, self.problem.objectives)
        with threadpool_limits(SURROGATE_THREADS):
            models = fit_models(self.problem, self.state.evaluated, self.state.screened, self.settings.seed,
                                self.jobs, SURROGATE_THREADS)
        return Exploration(t, self.state.screened, self.rounds, self.stop_reason or "", models,
                           None if best is None else int(best))

    def _progress(self, empty_round: bool) -> Progress:
        return Progress(len(self.state.evaluated), len(self.state.screened), self.rounds_without_move, empty_round)

    def _initial_design(self) -> np.ndarray:
        """The initial sample, screened; designs that screen invalid are replaced from a space-filling pool."""
        encoding, settings, state = self.problem.encoding, self.settings, self.state
        size = settings.initial or initial_size(encoding.dim, settings.budget)
        X = state.screen(initial_design(encoding, size, settings.seed), 0)
        spare = pool(encoding, 8 * size, settings.seed + 1)
        spare = spare[far_from(state.X(state.screened), spare)]  # designs not screened yet
        while len(X) < size and state.screens_left > 0 and len(spare):
            take, spare = spare[: size - len(X)], spare[size - len(X):]
            X = np.vstack([X, state.screen(take, 0)])
        return X[:size]

    def _propose(self, want: int) -> np.ndarray:
        """The search's designs for a batch of `want`, with its spares, on surrogates of everything verified."""
        state, objectives = self.state, list(self.problem.objectives)
        verified = state.evaluated[objectives].to_numpy(float).copy()
        verified[~state.evaluated[MEETS_JUDGED].to_numpy(bool)] = np.nan
        with threadpool_limits(SURROGATE_THREADS):
            models = fit_models(self.problem, state.evaluated, state.screened, self.settings.seed, self.jobs,
                                SURROGATE_THREADS)
            return propose(self.problem.encoding, models, want, state.X(state.screened), verified,
                           self.settings.seed + self.round_index, SPARES_PER_DESIGN * want)


def explore(problem: DesignProblem, settings: ExplorerSettings, jobs: int = 1) -> Exploration:
    """Ask and tell until a stop rule fires (see the module doc); every verified design, the rounds and the
    final models."""
    explorer = Explorer(problem, settings, jobs)
    while (X := explorer.ask()) is not None:
        explorer.tell(X, problem.evaluate(X) if len(X) else None)
    return explorer.result()
