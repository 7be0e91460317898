"""Constrained multi-objective search on the surrogates, and which designs to verify next.

NSGA-II (pymoo) minimises the predicted objectives subject to every predicted requirement margin
>= 0 and P(buildable) >= 1/2, over the unit cube with discrete axes snapped to their values. From its
final population the designs to verify are, in order:
1. the predicted choice: the predicted-feasible design with the smallest first objective;
2. then the predicted-feasible, non-dominated designs farthest (in objectives scaled to the predicted
   front's range) from every design already verified or picked, so the verified front fills in where
   it has gaps;
3. while the surrogates predict nothing feasible: the designs with the smallest predicted total
   violation, spread in the design space, one fewer than the batch;
4. the rest of the batch (at least one pick of a batch of two or more while nothing is predicted
   feasible): the designs most likely to be feasible over a space-filling sample, the margins'
   uncertainty included, so the search also looks where the surrogates are unsure.
After the batch come `spare` further designs of step 4, in order: the explorer screens them when proposals of the
batch screen invalid, so that a round still verifies a full batch (a core is not left idle for a round).
Designs already screened (verified, or found invalid) are never proposed again.
"""

from __future__ import annotations

import numpy as np

from seadesign.explore.doe import pool, unique_rows
from seadesign.explore.encoding import Encoding
from seadesign.explore.models import Models
from seadesign.sweep.rank import pareto_front

POPULATION = 64
GENERATIONS = 60
SAME_DESIGN = 1e-4  # unit-cube distance under which two designs are the same design
EXPLORE_SAMPLE = 2048  # space-filling points searched for the most-likely-feasible design


def _surrogate_problem(encoding: Encoding, models: Models):
    from pymoo.core.problem import Problem as PymooProblem

    class OnSurrogates(PymooProblem):
        def __init__(self) -> None:
            super().__init__(n_var=encoding.dim, n_obj=len(models.objectives), n_ieq_constr=len(models.margins) + 1,
                             xl=0.0, xu=1.0)

        def _evaluate(self, X, out, *args, **kwargs):
            X = encoding.snap(X)
            out["F"] = models.predict(models.objectives, X)[0]
            margins = models.predict(models.margins, X)[0]
            out["G"] = np.column_stack([-np.nan_to_num(margins, nan=0.0),
                                        0.5 - models.classifier.predict_proba(X)])

    return OnSurrogates()


def far_from(done: np.ndarray, X: np.ndarray) -> np.ndarray:
    """Rows of X not within SAME_DESIGN of a row of `done`."""
    if len(done) == 0 or len(X) == 0:
        return np.ones(len(X), bool)
    d = np.linalg.norm(X[:, None, :] - done[None, :, :], axis=2)
    return d.min(axis=1) > SAME_DESIGN


def _spread(points: np.ndarray, anchors: np.ndarray, n: int) -> list[int]:
    """Greedy max-min picks of `n` rows of `points` away from `anchors` (and from each other)."""
    picks: list[int] = []
    ref = anchors.copy()
    for _ in range(min(n, len(points))):
        d = np.full(len(points), np.inf) if len(ref) == 0 else \
            np.linalg.norm(points[:, None, :] - ref[None, :, :], axis=2).min(axis=1)
        d[picks] = -np.inf
        i = int(np.argmax(d))
        picks.append(i)
        ref = np.vstack([ref, points[i]]) if len(ref) else points[i:i + 1]
    return picks


def surrogate_optimum(encoding: Encoding, models: Models, seed: int):
    """NSGA-II on the surrogates: the final population (snapped, unique), its predicted objectives, margins
    and feasibility (every predicted margin >= 0 and P(buildable) >= 1/2)."""
    from pymoo.algorithms.moo.nsga2 import NSGA2
    from pymoo.optimize import minimize

    res = minimize(_surrogate_problem(encoding, models), NSGA2(pop_size=POPULATION), ("n_gen", GENERATIONS),
                   seed=seed, verbose=False)
    X = unique_rows(encoding.snap(res.pop.get("X")))
    F = models.predict(models.objectives, X)[0]
    margins = models.predict(models.margins, X)[0]
    ok = (np.nan_to_num(margins, nan=0.0) >= 0).all(axis=1) & (models.classifier.predict_proba(X) >= 0.5)
    return X, F, margins, ok


def propose(encoding: Encoding, models: Models, n: int, screened_X: np.ndarray, verified_F: np.ndarray,
            seed: int, spare: int = 0) -> np.ndarray:
    """Up to `n` designs to verify, then up to `spare` replacements (see the module doc), none of `screened_X`
    (every design screened so far); `verified_F` are the solved designs' objectives (rows of NaN where not
    feasible)."""
    X, F, margins, ok = surrogate_optimum(encoding, models, seed)
    new = far_from(screened_X, X)
    X, F, margins, ok = X[new], F[new], margins[new], ok[new]
    picks: list[np.ndarray] = []
    if ok.any():
        Xf, Ff = X[ok], F[ok]
        front = pareto_front(Ff)
        Xf, Ff = Xf[front], Ff[front]
        first = int(np.argmin(Ff[:, 0]))
        picks.append(Xf[first])
        lo, span = Ff.min(axis=0), np.maximum(np.ptp(Ff, axis=0), 1e-12)
        known = verified_F[np.isfinite(verified_F).all(axis=1)]
        anchors = np.vstack([(known - lo) / span, ((Ff[first] - lo) / span)[None]])
        rest = np.delete(np.arange(len(Xf)), first)
        picks += [Xf[rest[i]] for i in _spread((Ff[rest] - lo) / span, anchors, n - 1)]
    else:
        violation = np.clip(-np.nan_to_num(margins, nan=0.0), 0, None).sum(axis=1)
        best = np.argsort(violation, kind="stable")[: max(4 * n, 1)]
        picks += [X[best[i]] for i in _spread(X[best], screened_X[:0], n - 1 if n >= 2 else n)]
    fill = n - len(picks) + spare  # the rest of the batch and the spares: the designs most likely to be feasible
    if fill > 0:
        sample = pool(encoding, EXPLORE_SAMPLE, seed)
        sample = sample[far_from(np.vstack([screened_X, *picks]) if picks else screened_X, sample)]
        if len(sample):
            picks += list(sample[np.argsort(-models.p_feasible(sample), kind="stable")[:fill]])
    return unique_rows(np.array(picks)) if picks else np.empty((0, encoding.dim))
