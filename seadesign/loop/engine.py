"""The loop: residual -> trace every undeclared candidate -> add the winner, refit all -> repeat.

Stopping rule (what "significant" means here): a candidate is accepted only when, fitted
together with the effects already added, it

1. cuts the held-out RMSE by at least `min_gain` (default 5 %) relative to the current model, and
2. lowers the training BIC by at least `min_bic_drop` (default 10, "very strong" evidence).

The winner is the accepted candidate with the lowest held-out RMSE, except that a candidate whose
fitted parameters sit on a search bound (a limit, not an estimate: the effect is being stretched
to imitate something else) wins only when no accepted candidate fits inside its bounds. The loop stops when no
candidate is accepted (or after `max_steps`). An effect is therefore only ever named when it
beats the model without it, and so the plain model, on held-out data. When the final
residual still fails the whiteness tests, the report says so and where the structure is.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Sequence

import numpy as np

from seadesign.loop.candidates import CANDIDATES
from seadesign.loop.fit import Fit, fit, warm_starts
from seadesign.loop.table import LoopData, LoopInputError, time_blocks
from seadesign.loop.whiteness import residual_tests


@dataclass
class TraceEntry:
    """One candidate tried at one step, with its fit's scores."""

    effect: str
    fit: Fit
    held_out_rmse: float
    bic: float
    aic: float
    accepted: bool
    at_bound: bool = False


@dataclass
class Step:
    """One added effect: the model before and after, and every candidate tried."""

    effect: str
    before: Fit
    after: Fit
    trace: list[TraceEntry]


@dataclass
class Explanation:
    """The loop's answer on one data set."""

    data: LoopData
    held: np.ndarray
    plain: Fit
    final: Fit
    steps: list[Step]
    last_trace: list[TraceEntry]
    tests_before: dict
    tests_after: dict
    settings: dict = field(default_factory=dict)

    @property
    def found(self) -> list[str]:
        return [s.effect for s in self.steps]

    def verdict(self) -> str:
        """One paragraph: what was found, and whether structure is left (and where)."""
        h0 = self.plain.errors["held_out"]["rmse"]
        h1 = self.final.errors["held_out"]["rmse"]
        unit = self.data.measured_unit
        if self.steps:
            text = (f"Added {', '.join(self.found)}: held-out RMSE {h0:.4g} -> {h1:.4g} {unit} "
                    f"({h0 / max(h1, 1e-300):.3g}x lower).")
        else:
            text = (f"No candidate effect gives a significant held-out improvement over the plain model "
                    f"(held-out RMSE {h0:.4g} {unit}); nothing is named.")
        s = self.tests_after["strongest"]
        if self.tests_after["white"]:
            text += " The residual passes the whiteness tests: no structure is left that the tests can see."
        else:
            text += (f" Structure is left in the residual, unexplained by the library: strongest against "
                     f"{s['signal']} at lag {s['lag_s']:.3g} s (correlation {s['correlation']:.3g}, "
                     f"binned share of variance {s['explained_share_binned']:.3g}).")
        return text


def _signals(data: LoopData) -> dict[str, np.ndarray]:
    return dict(data.signals)


def explain(data: LoopData, declared: Sequence[str] = (), *, min_gain: float = 0.05, min_bic_drop: float = 10.0,
            max_steps: int = 4, n_blocks: int = 10, held_out_blocks: tuple[int, ...] = (2, 7),
            candidates: Sequence[str] | None = None) -> Explanation:
    """Run the loop on `data`; `declared` effects (already in the prediction) are not tried."""
    known = {c.key for c in CANDIDATES}
    for key in [*declared, *(candidates or [])]:
        if key not in known:
            raise LoopInputError(f"unknown effect '{key}'; the library has: {', '.join(sorted(known))}")
    pool = [c.key for c in CANDIDATES if c.applicable(data) and c.key not in declared
            and (candidates is None or c.key in candidates)]
    held = time_blocks(data.n, n_blocks, held_out_blocks)
    plain = fit(data, (), held)
    current, steps, trace = plain, [], []
    for _ in range(max_steps):
        trace = []
        base_h = current.errors["held_out"]["rmse"]
        warm = warm_starts(current, data)
        for key in pool:
            if key in current.keys:
                continue
            f = fit(data, current.keys + (key,), held, warm)
            h = f.errors["held_out"]["rmse"]
            ok = h <= (1.0 - min_gain) * base_h and f.bic <= current.bic - min_bic_drop
            pinned = any(p["at_bound"] for p in f.parameters()[key].values())
            trace.append(TraceEntry(key, f, h, f.bic, f.aic, ok, pinned))
        trace.sort(key=lambda t: t.held_out_rmse)
        winners = sorted((t for t in trace if t.accepted), key=lambda t: t.at_bound)  # stable: RMSE order kept
        if not winners:
            break
        best = winners[0]
        steps.append(Step(best.effect, current, best.fit, trace))
        current = best.fit
    sig = _signals(data)
    return Explanation(
        data=data, held=held, plain=plain, final=current, steps=steps,
        last_trace=trace,
        tests_before=residual_tests(data.measured - plain.prediction, data.time, sig),
        tests_after=residual_tests(data.measured - current.prediction, data.time, sig),
        settings={"min_gain": min_gain, "min_bic_drop": min_bic_drop, "max_steps": max_steps,
                  "n_blocks": n_blocks, "held_out_blocks": list(held_out_blocks), "declared": list(declared),
                  "candidates": pool},
    )
