"""Every surrogate of a problem, fitted together: one Gaussian process per objective, margin and
output, and the feasibility classifier; predictions of the requirement margins and objectives."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np
import pandas as pd
from scipy.stats import norm

from seadesign.explore.problem import SOLVED, VALID, DesignProblem
from seadesign.explore.surrogate import FeasibilityClassifier, LooError, Surrogate


@dataclass
class Models:
    """Fitted surrogates by column name, and the classifier of where designs can be built."""

    surrogates: dict[str, Surrogate]
    classifier: FeasibilityClassifier
    objectives: tuple[str, ...]
    margins: tuple[str, ...]
    unjudged: Callable[[str, np.ndarray], np.ndarray] | None = None  # (column, X) -> where it cannot be judged

    def predict(self, columns, X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(n, len(columns)) means and standard deviations; NaN (std inf) where the problem says a margin
        cannot be judged (e.g. the strain of a material without an allowable strain)."""
        X = np.atleast_2d(X)
        means, sds = [], []
        for c in columns:
            mean, sd = self.surrogates[c].predict(X, return_std=True)
            if self.unjudged is not None and c in self.margins:
                skip = self.unjudged(c, X)
                mean, sd = np.where(skip, np.nan, mean), np.where(skip, np.inf, sd)
            means.append(mean)
            sds.append(sd)
        return np.column_stack(means), np.column_stack(sds)

    def p_feasible(self, X: np.ndarray) -> np.ndarray:
        """P(every requirement met and the design buildable), the margins' errors taken as independent."""
        mean, sd = self.predict(self.margins, X)
        p = norm.cdf(mean / np.maximum(sd, 1e-12))
        p[~np.isfinite(mean)] = 1.0  # a requirement with no surrogate yet (nothing judged): no information
        return np.prod(p, axis=1) * self.classifier.predict_proba(X)

    def loo_errors(self, columns) -> dict[str, LooError]:
        return {c: self.surrogates[c].loo_error() for c in columns}


def _fit(model, X: np.ndarray, y: np.ndarray):
    return model.fit(X, y)


def fit_models(problem: DesignProblem, evaluated: pd.DataFrame, screened: pd.DataFrame, seed: int, jobs: int = 1,
               threads: int = 1) -> Models:
    """Fit every surrogate on the solved designs (a screened column also on every valid screened design)
    and the classifier on every screened design; X columns are the unit-cube coordinates `x0..`. The fits are
    independent and seeded: `jobs` processes (joblib's loky, `threads` BLAS threads each) give the same models
    as one."""
    from joblib import Parallel, delayed, parallel_config

    xcols = [f"x{i}" for i in range(problem.encoding.dim)]
    solved = evaluated[evaluated[SOLVED].astype(bool)]
    valid = screened[screened[VALID].astype(bool)]
    columns = list(dict.fromkeys((*problem.objectives, *problem.margins, *problem.outputs)))
    # the classifier first: the slowest fit
    tasks = [(FeasibilityClassifier(seed), screened[xcols].to_numpy(float), screened[VALID].to_numpy(bool))]
    for j, column in enumerate(columns):
        data = valid if column in problem.screened else solved
        positive = column not in problem.margins  # physical outputs: modelled in log space when all positive
        tasks.append((Surrogate(log=positive, seed=seed + j), data[xcols].to_numpy(float),
                      data[column].to_numpy(float)))
    with parallel_config(backend="loky", inner_max_num_threads=threads):
        classifier, *fitted = Parallel(n_jobs=jobs)(delayed(_fit)(*task) for task in tasks)
    return Models(dict(zip(columns, fitted)), classifier, problem.objectives, problem.margins,
                  getattr(problem, "unjudged", None))
