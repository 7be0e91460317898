"""The explorer's answer: the chosen design, which requirements are active or missed there, and the
evidence from the surrogates about the space that was not solved.

The choice is always a solved design (`problem.best_index`): the feasible design with the smallest
first objective, or, with none feasible, the one that misses its requirements by the least in total.
A requirement is active at the choice when it is met with less than ACTIVE_MARGIN to spare. The
evidence is a prediction and says so: the surrogates' optimum over the whole space, with its
uncertainty, and the highest probability of feasibility found over a space-filling sample.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from seadesign.explore.doe import pool
from seadesign.explore.encoding import Encoding
from seadesign.explore.explorer import Exploration
from seadesign.explore.search import surrogate_optimum

ACTIVE_MARGIN = 0.05  # met with less than 5 % of its limit to spare: the requirement is active
EVIDENCE_SAMPLE = 4096  # space-filling designs searched for the highest predicted probability of feasibility


@dataclass(frozen=True)
class Decision:
    """What the explorer answers, in words and numbers."""

    index: int | None  # row of `Exploration.evaluated` (None: nothing solved)
    feasible: bool
    active: tuple[tuple[str, float], ...]  # (requirement, margin) met with less than ACTIVE_MARGIN to spare
    missed: tuple[tuple[str, float], ...]  # (requirement, margin < 0), worst first
    not_judged: tuple[str, ...]  # requirements that cannot be judged at the choice, with why
    predicted: str  # the surrogates' evidence over the space not solved (a prediction, labelled so)
    p_feasible_max: float  # highest predicted probability of feasibility over the sample


def _evidence(encoding: Encoding, exploration: Exploration, words: dict[str, str], objective_words: str,
              seed: int) -> tuple[str, float]:
    models = exploration.models
    sample = np.vstack([pool(encoding, EVIDENCE_SAMPLE, seed), surrogate_optimum(encoding, models, seed)[0]])
    p = models.p_feasible(sample)
    X, F, margins, ok = surrogate_optimum(encoding, models, seed)
    if ok.any():
        i = int(np.flatnonzero(ok)[np.argmin(F[ok, 0])])
        mean, sd = models.predict(models.objectives[:1], X[i:i + 1])
        text = (f"Predicted, not solved: the surrogates' lightest feasible design over the whole space is "
                f"{_describe(encoding, X[i])}, {objective_words} {mean[0, 0]:.3g} +- {sd[0, 0]:.2g}, "
                f"P(feasible) {models.p_feasible(X[i:i + 1])[0]:.2f}.")
    else:
        violation = np.clip(-np.nan_to_num(margins, nan=0.0), 0, None).sum(axis=1)
        i = int(np.argmin(violation))
        mean, sd = models.predict(models.margins, X[i:i + 1])
        j = int(np.nanargmin(mean[0]))
        text = (f"Predicted, not solved: the surrogates find no feasible design anywhere in the space. Their least "
                f"total violation is {violation[i]:.3g} at {_describe(encoding, X[i])}, where '{words[models.margins[j]]}' "
                f"is missed by {-mean[0, j]:.1%} +- {sd[0, j]:.1%} (one standard deviation).")
    text += (f" The highest predicted probability that a design meets every requirement, over {len(sample)} designs "
             f"spread over the space, is {p.max():.1%}.")
    return text, float(p.max())


def _describe(encoding: Encoding, x: np.ndarray) -> str:
    from seadesign.design.space import candidate_name

    return candidate_name(encoding.decode(x))


def decide(exploration: Exploration, encoding: Encoding, requirement_words: dict[str, str],
           not_judged_why: dict[str, str], objective_words: str, seed: int = 0) -> Decision:
    """The decision over an exploration; `requirement_words` maps margin columns to words, `not_judged_why`
    says why a margin column may be NaN (e.g. a material without an allowable strain)."""
    t = exploration.evaluated
    index = exploration.best
    predicted, p_max = _evidence(encoding, exploration, requirement_words, objective_words, seed)
    if index is None:
        return Decision(None, False, (), (), (), predicted, p_max)
    row = t.loc[index]
    margins = {c: float(row[c]) for c in requirement_words}
    active = tuple((requirement_words[c], m) for c, m in margins.items() if 0 <= m < ACTIVE_MARGIN)
    missed = tuple(sorted(((requirement_words[c], m) for c, m in margins.items() if m < 0), key=lambda p: p[1]))
    needs = str(row.get("not_judged", "") or "")  # the spring problem names the missing data and the values
    unjudged = tuple(needs.split("; ")) if needs else tuple(
        f"{requirement_words[c]}: {not_judged_why.get(c, 'its load is not carried')}"
        for c, m in margins.items() if math.isnan(m))
    return Decision(index, bool(row["feasible"]), active, missed, unjudged, predicted, p_max)

