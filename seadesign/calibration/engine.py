"""The loop: refit the declared model, trace every undeclared effect, add the winner, repeat; then test
what was declared.

1. The declared model as given (`reference`): the spring (k, or the large-deflection curve) and the
   declared effects at their declared values. Its error is the "before".
2. The declared model refitted (`base`): every declared parameter free, started at its declared
   value, and the stiffness scale (the declared k is always refitted).
3. Forward selection: each undeclared effect of the library that applies (and on a bench with the spring's own
   part, the material law's shape, `loop.law_family`) is fitted together with
   the current model (screened first with the declared effects but the stiffness scale held; the
   `screen` best, and any the screen accepts, refitted with everything free); it is accepted when it cuts the held-out RMSE by at least `min_gain` (5 %)
   and lowers the training BIC by at least `min_bic_drop` (10, "very strong" evidence). The winner
   is the accepted one with the lowest held-out RMSE, except that a fit pinned at a search bound
   wins only when no accepted fit lies inside its bounds. When the runner-up is as good (held-out
   RMSE within `ambiguity`, 3 %) and the two together do not beat the winner by `min_gain`, the data
   cannot tell them apart: the step is reported as an ambiguity with both fits, not a single name (a law shape
   then goes first: the part's own law before a phenomenological term).
   A sensor step is proposed at the instant change-point detection finds in the current residual, searched
   between 10 % and 90 % of the record (none when the largest jump is at that limit), then found again in the
   residual of its own fit without it, where the current model no longer bends around the jump, until it stays.
4. Declared effects are tested: one that can be dropped without raising the held-out RMSE by
   `min_gain` (or the BIC by `min_bic_drop`) is unsupported and dropped; the stiffness scale differs
   from the declared k (and is named) only when holding it at 1 fails the same test.

An effect is therefore only named when it beats the model without it on held-out data.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Sequence

import numpy as np

from seadesign.effects import Effect, SensorStep, StiffnessScale
from seadesign.calibration.changepoint import best_split
from seadesign.calibration.model import EffectModel, Fit, evaluate
from seadesign.calibration.table import LoopData, LoopInputError, time_blocks
from seadesign.calibration.terms import CANDIDATES, LAW_SHAPES, Term, applicable
from seadesign.calibration.whiteness import residual_tests

SCALE = "stiffness_scale"


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
    """One added effect: the model before and after, every candidate tried, and (an ambiguity) the
    equally good alternative."""

    effect: str
    before: Fit
    after: Fit
    trace: list[TraceEntry]
    alternative: TraceEntry | None = None


@dataclass
class DeclaredCheck:
    """A declared effect after refitting: declared and fitted values, and whether the data supports it."""

    name: str
    key: str
    declared: dict[str, float]
    fitted: dict[str, dict]
    supported: bool
    held_out_rmse_without: float
    held_out_rmse_with: float

    def text(self) -> str:
        parts = [f"{p} declared {self.declared[p]:.4g}, data says {v['value']:.4g} +- {v['uncertainty']:.2g} {v['unit']}"
                 + "".join(f" (correlated with {other}, r = {r:+.2f}: they trade off; the uncertainty covers it)"
                           for other, r in v.get("correlated_with", {}).items())
                 for p, v in self.fitted.items() if not v["held"]]
        if self.key == SCALE:
            verdict = "differs from the declared k" if self.supported else "consistent with the declared k"
        else:
            verdict = "supported" if self.supported else "unsupported by the data (dropped)"
        return f"{self.name}: {'; '.join(parts)} ({verdict}; held-out RMSE without it {self.held_out_rmse_without:.4g})"


@dataclass
class Explanation:
    """The loop's answer on one data set."""

    data: LoopData
    held: np.ndarray
    plain: Fit
    base: Fit
    final: Fit
    steps: list[Step]
    last_trace: list[TraceEntry]
    declared: list[DeclaredCheck]
    tests_before: dict
    tests_after: dict
    settings: dict = field(default_factory=dict)

    @property
    def added(self) -> list[str]:
        """Undeclared effects added, in order (an ambiguous step under its winner's name)."""
        return [s.effect for s in self.steps]

    @property
    def found(self) -> list[str]:
        """Named effects: the stiffness scale when it differs from the declared k, then the effects added."""
        scale = [c.name for c in self.declared if c.key == SCALE and c.supported]
        return scale + self.added

    @property
    def ambiguities(self) -> list[tuple[str, str]]:
        return [(s.effect, s.alternative.effect) for s in self.steps if s.alternative is not None]

    @property
    def unsupported(self) -> list[str]:
        return [c.name for c in self.declared if c.key != SCALE and not c.supported]

    def verdict(self) -> str:
        """One paragraph: what was found, what the declared model's parameters became, structure left."""
        h0, h1 = self.plain.errors["held_out"]["rmse"], self.final.errors["held_out"]["rmse"]
        unit = self.data.measured_unit
        named = [f"{a} or {b} (the data cannot tell them apart)" if (a, b) in self.ambiguities else a
                 for a, b in [(n, dict(self.ambiguities).get(n)) for n in self.found]]
        if named:
            text = f"Found {', '.join(named)}: held-out RMSE {h0:.4g} -> {h1:.4g} {unit} ({h0 / max(h1, 1e-300):.3g}x lower)."
        else:
            text = (f"No effect gives a significant held-out improvement over the declared model "
                    f"(held-out RMSE {h0:.4g} -> {h1:.4g} {unit}); nothing is named.")
        for t in self.final.terms:
            if t.on_torque:
                value = self.final.values[t.name]
                lag = (f"delayed by {value['delay_s'] * 1e3:.3g} ms" if "delay_s" in value else
                       f"low-pass filtered with a time constant of {value['time_constant_s'] * 1e3:.3g} ms")
                text += f" The torque reading lags the deflection reading: {lag} ({t.name})."
        if self.unsupported:
            text += f" Declared but unsupported by the data: {', '.join(self.unsupported)}."
        if self.data.coverage is not None:
            text += " " + self.data.coverage.text()
        text += "".join(" " + note for note in self.data.notes)
        if any(k in self.data.shapes for k in LAW_SHAPES):
            text += " " + self.law_shape_text()
        if not self.final.converged:
            text += " The final fit did not converge (evaluation limit): its numbers are not a result."
        s = self.tests_after["strongest"]
        if self.tests_after["white"]:
            text += " The residual passes the whiteness tests: no structure is left that the tests can see."
        else:
            text += (f" Structure is left in the residual, unexplained by the library: strongest against "
                     f"{s['signal']} at lag {s['lag_s']:.3g} s (correlation {s['correlation']:.3g}, "
                     f"binned share of variance {s['explained_share_binned']:.3g}).")
        return text

    def law_shape_text(self) -> str:
        """Which law shape the held-out error prefers, or that the data cannot tell the shapes apart."""
        named = next((t.key for t in self.final.terms if t.key in LAW_SHAPES), None)
        if named is None:
            tried = [t for t in self.last_trace if t.effect in LAW_SHAPES]
            best = min(tried, key=lambda t: t.held_out_rmse, default=None)
            own = self.final.errors["held_out"]["rmse"]
            scores = "" if best is None else \
                f" (best: {best.effect}, held-out RMSE {best.held_out_rmse:.4g} against {own:.4g})"
            return (f"No law shape beats the material's own on held-out data{scores}: over this file's strains the "
                    f"Mooney-Rivlin and Yeoh shapes and the material's law are indistinguishable, so the shape is not "
                    f"identified and mu's uncertainty in the calibration includes the shape-free fit's.")
        step = next(s for s in self.steps if s.effect == named)
        ours = next(t.held_out_rmse for t in step.trace if t.effect == named)
        if step.alternative is not None and step.alternative.effect in LAW_SHAPES:
            return (f"The data cannot tell the {named} and {step.alternative.effect} shapes apart over this file's "
                    f"strains (held-out RMSE {ours:.4g} and {step.alternative.held_out_rmse:.4g}); the fitted law is "
                    f"the {named} one.")
        other = [t for t in step.trace if t.effect in LAW_SHAPES and t.effect != named]
        against = f" over {other[0].effect} ({other[0].held_out_rmse:.4g})" if other else ""
        return f"The held-out error prefers the {named} shape (held-out RMSE {ours:.4g}){against}."


def _term(key: str, data: LoopData, current: Fit) -> Term | None:
    """A fresh candidate term for `key` (a sensor step at the instant the current residual jumps)."""
    if key in LAW_SHAPES:
        return Term(key, data.shapes[key])
    if key != "sensor_step":
        return Term.of(key)
    taken = [current.values[t.name]["time_s"] for t in current.terms if t.key == "sensor_step"]
    index = _jump(data, _residual(data, current), taken)
    if index is None:
        return None
    name = "sensor_step" if not taken else f"sensor_step_{len(taken) + 1}"
    return _step(data, name, index)


def _residual(data: LoopData, fit: Fit) -> np.ndarray:
    """measured - predicted, zero on the samples the model does not cover (past the torque curve's end)."""
    return np.where(data.in_range, data.measured - fit.prediction, 0.0)


def _jump(data: LoopData, residual: np.ndarray, taken: list[float]) -> int | None:
    """Index where `residual` jumps, at least a tenth of the record from either end and from the steps `taken`
    (their instants, s); None when the largest jump is at that limit (it may lie beyond: nearer an end a jump
    is, over most of the record, an offset)."""
    return best_split(residual, min_size=max(10, data.n // 10), interior=True,
                      exclude=[int(np.searchsorted(data.time - data.time[0], s)) for s in taken])


def _step(data: LoopData, name: str, index: int) -> Term:
    return Term(name, SensorStep(name, time_s=float(data.time[index] - data.time[0])))


def _relocated(data: LoopData, held: np.ndarray, current: Fit, term: Term, f: Fit,
               fixed: dict) -> tuple[Term, Fit] | None:
    """A candidate sensor step's instant found again in the residual of its fit `f` without the step, and refitted,
    until it stays (at most three times): the current model, fitted without the jump, has bent around it, and
    its residual can put the jump samples away. None when the jump is no longer inside the search window."""
    taken = [current.values[t.name]["time_s"] for t in current.terms if t.key == "sensor_step"]
    for _ in range(3):
        without = evaluate(data, current.terms, f.values, held)
        index = _jump(data, _residual(data, without), taken)
        if index is None:
            return None
        moved = _step(data, term.name, index)
        if moved.effect.values["time_s"] == term.effect.values["time_s"]:
            break
        term = moved
        f = _fit(data, current.terms + [term], held, current.values, fixed=fixed)
    return term, f


def _pinned(f: Fit, name: str) -> bool:
    return any(p["at_bound"] for p in f.parameters()[name].values())


def _fit(data: LoopData, terms: list[Term], held: np.ndarray, warm: dict | None = None,
         fixed: dict | None = None) -> Fit:
    return EffectModel(terms, fixed).fit(data, held, warm).fit_


def explain(data: LoopData, declared: Sequence[Effect] = (), *, exclude: Sequence[str] = (), min_gain: float = 0.05,
            min_bic_drop: float = 10.0, ambiguity: float = 0.03, max_steps: int = 4, screen: int = 3, n_blocks: int = 10,
            held_out_blocks: tuple[int, ...] = (2, 7), candidates: Sequence[str] | None = None) -> Explanation:
    """Run the loop on `data` with the `declared` effects (library effects with their declared values);
    `exclude`: library keys not traced (effects a generic table's prediction already holds)."""
    for key in [*exclude, *(candidates or [])]:
        if key not in CANDIDATES + LAW_SHAPES:
            raise LoopInputError(f"unknown effect '{key}'; the loop traces: {', '.join(sorted(CANDIDATES + LAW_SHAPES))}")
    held = time_blocks(data.n, n_blocks, held_out_blocks)
    decl = ([Term(SCALE, StiffnessScale(), declared=True)] if applicable(SCALE, data) else []) + \
           [Term(e.name, e, declared=True) for e in declared]
    declared_keys = {t.key for t in decl}
    pool = [k for k in CANDIDATES + LAW_SHAPES if applicable(k, data) and k not in declared_keys and k not in exclude
            and (candidates is None or k in candidates)]
    plain = evaluate(data, decl, {t.name: dict(t.effect.values) for t in decl}, held)
    base = _fit(data, decl, held)
    current, steps, trace = base, [], []

    def gate(f: Fit, ref: Fit) -> bool:
        return f.errors["held_out"]["rmse"] <= (1 - min_gain) * ref.errors["held_out"]["rmse"] and f.bic <= ref.bic - min_bic_drop

    for _ in range(max_steps):
        trace = _trace(data, held, current, pool, gate, screen)
        trace.sort(key=lambda t: t.held_out_rmse)
        winners = sorted((t for t in trace if t.accepted), key=lambda t: t.at_bound)  # stable: RMSE order kept
        if not winners:
            break
        best = winners[0]
        alt = _alternative(data, held, best, winners[1:], ambiguity, min_gain)
        if alt is not None and alt.effect in LAW_SHAPES and best.effect not in LAW_SHAPES:
            best, alt = alt, best  # as good: the part's own law before a phenomenological term
        steps.append(Step(best.effect, current, best.fit, trace, alt))
        current = best.fit
    checks, current = _check_declared(data, held, current, decl, gate)
    sig = dict(data.signals)
    return Explanation(
        data=data, held=held, plain=plain, base=base, final=current, steps=steps, last_trace=trace, declared=checks,
        tests_before=residual_tests(_residual(data, plain), data.time, sig),
        tests_after=residual_tests(_residual(data, current), data.time, sig),
        settings={"min_gain": min_gain, "min_bic_drop": min_bic_drop, "ambiguity": ambiguity, "max_steps": max_steps,
                  "screen": screen, "n_blocks": n_blocks, "held_out_blocks": list(held_out_blocks),
                  "declared": [t.name for t in decl], "excluded": list(exclude), "candidates": pool},
    )


def _trace(data: LoopData, held: np.ndarray, current: Fit, pool: list[str], gate, screen: int) -> list[TraceEntry]:
    """Every candidate fitted with the current model: first screened (the declared effects but the stiffness
    scale held), then the `screen` best and every one the screen already accepts refitted with all free."""
    held_values = {t.name: current.values[t.name] for t in current.terms if t.declared and t.key != SCALE}
    screened = []
    taken = {t.candidate for t in current.terms}
    for key in pool:
        if key in taken and key != "sensor_step" or key in LAW_SHAPES and taken & set(LAW_SHAPES):
            continue  # one law shape at a time
        term = _term(key, data, current)
        if term is None:
            continue
        f = _fit(data, current.terms + [term], held, current.values, fixed=held_values)
        if term.key == "sensor_step":
            located = _relocated(data, held, current, term, f, held_values)
            if located is None:
                continue
            term, f = located
        screened.append((term, f))
    screened.sort(key=lambda tf: tf[1].errors["held_out"]["rmse"])
    trace = []
    for i, (term, f) in enumerate(screened):
        if i < screen or gate(f, current):
            f = _fit(data, current.terms + [term], held, {**current.values, term.name: f.values[term.name]})
        trace.append(TraceEntry(term.name, f, f.errors["held_out"]["rmse"], f.bic, f.aic, gate(f, current),
                                _pinned(f, term.name)))
    return trace


def _alternative(data, held, best: TraceEntry, others: list[TraceEntry], ambiguity: float,
                 min_gain: float) -> TraceEntry | None:
    """The runner-up when the data cannot tell it from the winner: within `ambiguity` in held-out RMSE, inside
    its bounds, and not adding `min_gain` when fitted together with the winner."""
    inside = [t for t in others if not t.at_bound]
    if not inside or best.at_bound:
        return None
    alt = inside[0]
    if alt.held_out_rmse > (1 + ambiguity) * best.held_out_rmse:
        return None
    both = _fit(data, best.fit.terms + [alt.fit.term(alt.effect)], held, {**best.fit.values, **alt.fit.values})
    return alt if both.errors["held_out"]["rmse"] > (1 - min_gain) * best.held_out_rmse else None


def _check_declared(data, held, current: Fit, decl: list[Term], gate) -> tuple[list[DeclaredCheck], Fit]:
    """Each declared effect against the model without it: drop the unsupported ones, weakest first, until
    every declared effect left is supported; then the scale against the final model with it held at 1."""
    checks: dict[str, DeclaredCheck] = {}
    while True:
        trials = [(t, _fit(data, [u for u in current.terms if u.name != t.name], held, current.values))
                  for t in decl if t.key != SCALE and t.name not in checks]
        weak = [(t, w) for t, w in trials if not gate(current, w)]
        if not weak:
            checks.update({t.name: _check(t, current, w, True) for t, w in trials})
            break
        t, without = min(weak, key=lambda tw: tw[1].errors["held_out"]["rmse"])
        checks[t.name] = _check(t, current, without, False)
        current = without
    for t in decl:
        if t.key == SCALE:
            without = _fit(data, current.terms, held, current.values, fixed={t.name: {"scale": 1.0}})
            checks[t.name] = _check(t, current, without, gate(current, without))
    return [checks[t.name] for t in decl], current


def _check(t: Term, with_: Fit, without: Fit, supported: bool) -> DeclaredCheck:
    return DeclaredCheck(t.name, t.key, dict(t.effect.values), with_.parameters()[t.name], supported,
                         without.errors["held_out"]["rmse"], with_.errors["held_out"]["rmse"])
