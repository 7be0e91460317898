"""A model of library effects fitted to data, in the estimator style of scikit-learn and PySINDy.

    model = EffectModel([Term("stiffness_scale", StiffnessScale(), declared=True), Term("dead_band", DeadBand())])
    model.fit(data, held)            # held: boolean mask of held-out samples (None: fit on all)
    model.predict(data); model.score(data, held); model.parameters()

All parameters of all terms are fitted together on the training samples by bounded least
squares (`scipy.optimize.least_squares`, trust-region reflective with the LSMR subproblem solver,
faster than its SVD with the same answer (docs/validation/timing.md); positive scale parameters in
log space; a parameter whose search bounds are equal is held, e.g. a step's instant). Search
spaces come from each effect (`Effect.search(data.scales())`); a declared term starts at its
declared values. The model is evaluated over the whole record (stateful effects need the history);
the optimiser sees at most `MAX_FIT_ROWS` evenly spaced training samples, errors and information
criteria use every training sample. Uncertainties: the sandwich cov = (J^T J)^-1 S (J^T J)^-1 n / (n - p) on
the fitted rows (rescaled to the full count), S the Newey-West sum of the products J_t r_t over lags up to
the smoother's window (~0.1 s), over which the smoothed input's noise correlates neighbouring residuals
(without it the scatter over noise draws was up to 2.1 times the uncertainty reported on a robot recording,
`tests/test_calibration_uncertainty.py`). Residuals of real recordings are correlated for longer (structure the model
lacks), so there these are lower bounds. AIC = n ln(SSR/n) + 2p, BIC = n ln(SSR/n) + p ln n (held
parameters count). A fit that ends without least_squares' convergence says so (`converged`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from itertools import product

import numpy as np
from scipy.optimize import least_squares

from seadesign.effects import Param
from seadesign.calibration.metrics import split_metrics
from seadesign.calibration.table import LoopData
from seadesign.calibration.terms import Term, predict, whole_record

MAX_FIT_ROWS = 8000
HAC_LAGS = 2
#: |correlation| of two parameters' estimates from which the report names them as trading off
CORRELATED = 0.5


def _hac(g: np.ndarray, lags: int) -> np.ndarray:
    """sum over t, s of w(|t - s|) g_t g_s^T with Bartlett weights w(l) = 1 - l / (lags + 1) (Newey-West)."""
    out = g.T @ g
    for lag in range(1, min(lags, g.shape[0] - 1) + 1):
        cross = g[lag:].T @ g[:-lag]
        out += (1.0 - lag / (lags + 1)) * (cross + cross.T)
    return out

Values = dict[str, dict[str, float]]


@dataclass
class Fit:
    """A fitted model's state: terms, parameters (value, uncertainty, unit) and scores."""

    terms: list[Term]
    values: Values
    sigma: Values
    units: dict[str, dict[str, str]]
    bounds: dict[str, dict[str, tuple[float, float]]]
    prediction: np.ndarray
    errors: dict[str, dict[str, float]]
    aic: float
    bic: float
    n_train: int
    converged: bool = True
    extra: dict = field(default_factory=dict)
    correlation: dict[tuple[str, str], dict[tuple[str, str], float]] = field(default_factory=dict)
    # (term, parameter) -> the other fitted parameters it is correlated with at |r| >= CORRELATED, and r
    covariance: dict[tuple[tuple[str, str], tuple[str, str]], float] = field(default_factory=dict)
    # ((term, parameter), (term, parameter)) -> covariance of the two estimates, over the fitted parameters

    @property
    def keys(self) -> tuple[str, ...]:
        return tuple(t.name for t in self.terms)

    def parameters(self) -> dict[str, dict[str, dict[str, float | str | bool]]]:
        """term -> parameter -> {value, uncertainty, unit, meaning, at_bound, held, correlated_with} (at_bound: the
        fit hit a search bound, so the value is a limit, not an estimate; a held parameter is never at a bound;
        correlated_with: "term.parameter" -> correlation r of the estimates, for |r| >= `CORRELATED`: the two trade
        off in the fit, and the uncertainty is the marginal one, which covers that trade-off)."""
        out: dict = {}
        for t in self.terms:
            docs = {p.name: p.doc for p in t.effect.parameters}
            for name, v in self.values[t.name].items():
                lo, hi = self.bounds[t.name][name]
                at_bound = lo < hi and bool(np.isclose(v, lo, rtol=1e-6, atol=0) or np.isclose(v, hi, rtol=1e-6, atol=0))
                out.setdefault(t.name, {})[name] = {
                    "value": float(v), "uncertainty": float(self.sigma[t.name][name]), "unit": self.units[t.name][name],
                    "meaning": docs[name], "at_bound": at_bound, "held": lo == hi,
                    "correlated_with": {f"{a}.{b}": r for (a, b), r in self.correlation.get((t.name, name), {}).items()}}
        return out

    def term(self, name: str) -> Term:
        return next(t for t in self.terms if t.name == name)


def display_unit(p: Param, data: LoopData) -> str:
    """A parameter's unit on `data`: the library's SEA unit, or on a generic table the table's units
    in place of Nm (measured) and rad (deflection)."""
    if data.spring is not None:
        return p.unit
    measured, deflection = data.measured_unit, data.unit("deflection")
    return p.unit.replace("Nm", "\0").replace("rad", deflection).replace("\0", measured)


def _correlated(cov: np.ndarray, names: list[tuple[str, str]]) -> dict:
    """(term, parameter) -> {other: r} for the pairs of estimates correlated at |r| >= CORRELATED."""
    sd = np.sqrt(np.clip(np.diag(cov), 0, None))
    with np.errstate(divide="ignore", invalid="ignore"):
        r = cov / np.outer(sd, sd)
    out: dict = {}
    for i, j in zip(*np.nonzero(np.abs(np.nan_to_num(r)) >= CORRELATED)):
        if i != j:
            out.setdefault(names[i], {})[names[j]] = float(r[i, j])
    return out


class EffectModel:
    """Terms (library effects) fitted jointly to a LoopData; `fit` returns self with `fit_` set."""

    def __init__(self, terms: list[Term], fixed: Values | None = None) -> None:
        names = [t.name for t in terms]
        if len(set(names)) != len(names):
            raise ValueError(f"term names must be unique: {names}")
        self.terms = list(terms)
        self.fixed = fixed or {}  # term -> parameter -> value held at that value
        self.fit_: Fit | None = None

    def _space(self, data: LoopData) -> tuple[list[tuple[str, str]], np.ndarray, np.ndarray, np.ndarray, list]:
        """(term, parameter) pairs, lower and upper bounds, log flags and each term's start options."""
        names, lo, hi, logs, options = [], [], [], [], []
        scales = data.scales()
        for t in self.terms:
            bounds, starts = t.effect.search(scales)
            if t.declared:  # refitted from the declared values
                starts = [{**starts[0], **t.effect.values}]
            for p in t.effect.parameters:
                a, b = bounds[p.name]
                if p.name in self.fixed.get(t.name, {}):
                    a = b = self.fixed[t.name][p.name]
                names.append((t.name, p.name))
                lo.append(a)
                hi.append(b)
                logs.append(p.name in t.effect.log_params and a > 0)
            options.append([[s[p.name] for p in t.effect.parameters] for s in starts])
        return names, np.array(lo, float), np.array(hi, float), np.array(logs, bool), options

    def _values(self, names: list[tuple[str, str]], x: np.ndarray) -> Values:
        out: Values = {t.name: {} for t in self.terms}
        for (term, name), v in zip(names, x):
            out[term][name] = float(v)
        return out

    def fit(self, data: LoopData, held: np.ndarray | None = None, warm: Values | None = None) -> "EffectModel":
        """Fit on the training samples (~held); `warm` gives start values per term (else its start options,
        every combination tried, the lowest training cost kept)."""
        held = np.zeros(data.n, bool) if held is None else held
        train = ~held & data.in_range
        names, lo, hi, logs, options = self._space(data)
        free = lo < hi
        to_u = lambda x: np.where(logs, np.log(np.where(logs, x, 1.0)), x)  # noqa: E731
        n = int(train.sum())
        rows = np.flatnonzero(train)[:: max(1, -(-n // MAX_FIT_ROWS))]
        y = data.measured[rows]
        pointwise = not whole_record(self.terms, data)
        sub = data.subset(rows) if pointwise else data
        warm = warm or {}
        combos = [[[warm[t.name][p.name] for p in t.effect.parameters]] if t.name in warm else opts
                  for t, opts in zip(self.terms, options)]
        best, x_best, converged = None, np.clip(lo, lo, hi), True
        if free.any():
            ulo, uhi = to_u(lo)[free], to_u(hi)[free]

            def full(uf):
                x = np.clip(lo, lo, hi)
                x[free] = np.clip(to_x_free(uf), lo[free], hi[free])
                return x

            def to_x_free(uf):
                return np.where(logs[free], np.exp(np.where(logs[free], uf, 0.0)), uf)

            def resid(uf):
                pred = predict(sub, self.terms, self._values(names, full(uf)))
                return (pred if pointwise else pred[rows]) - y

            for combo in product(*combos):
                x0 = np.clip(np.concatenate([np.asarray(c, float) for c in combo]) if combo else lo, lo, hi)
                u0 = to_u(x0)[free]
                u0 = np.clip(u0, ulo + 1e-9 * (uhi - ulo), uhi - 1e-9 * (uhi - ulo))
                res = least_squares(resid, u0, bounds=(ulo, uhi), x_scale="jac", method="trf", max_nfev=100 * len(u0),
                                    tr_solver="lsmr" if len(u0) > 1 else "exact")  # lsmr's 2-D subspace needs 2
                if best is None or res.cost < best.cost:
                    best = res
            x_best = full(best.x)
            converged = best.status > 0
        else:
            x_best = lo.copy()
        values = self._values(names, x_best)
        pred = predict(data, self.terms, values)
        ssr = float(np.sum((data.measured[train] - pred[train]) ** 2))
        sigma = np.zeros(len(names))
        correlation: dict = {}
        covariance: dict = {}
        if best is not None:
            with np.errstate(over="ignore", divide="ignore"):
                jac = best.jac * np.where(logs[free], 1.0 / x_best[free], 1.0)  # d/dx = d/du / x for log parameters
            try:
                bread = np.linalg.pinv(jac.T @ jac)
                spacing = rows[1] - rows[0] if rows.size > 1 else 1
                meat = _hac(jac * (data.measured[rows] - pred[rows])[:, None], -(-data.window // spacing))
                cov = bread @ meat @ bread * (rows.size / max(n - int(free.sum()), 1))
                sigma[free] = np.sqrt(np.clip(np.diag(cov), 0, None))
                fitted = [n for n, f in zip(names, free) if f]
                correlation = _correlated(cov, fitted)
                covariance = {(a, b): float(cov[i, j]) for i, a in enumerate(fitted) for j, b in enumerate(fitted)}
            except np.linalg.LinAlgError:
                sigma[free] = np.nan
        held_dt = [(t, p) for (t, p), f in zip(names, free) if not f and p == "time_s"]
        for t, p in held_dt:  # an instant held from change-point detection is known to one sample
            sigma[names.index((t, p))] = data.dt
        p_count = len(names)
        ll = n * np.log(max(ssr, 1e-300) / n)
        by_term = {t.name: {p.name: display_unit(p, data) for p in t.effect.parameters} for t in self.terms}
        bounds = {t.name: {} for t in self.terms}
        for (t, p), a, b in zip(names, lo, hi):
            bounds[t][p] = (float(a), float(b))
        self.fit_ = Fit(list(self.terms), values, self._values(names, sigma), by_term, bounds, pred,
                        split_metrics(data.measured, pred, held, data.in_range), float(ll + 2 * p_count),
                        float(ll + p_count * np.log(n)), n, converged, correlation=correlation, covariance=covariance)
        return self

    def predict(self, data: LoopData) -> np.ndarray:
        """The fitted model's prediction on `data` (which may be another record with the same signals)."""
        if self.fit_ is None:
            raise ValueError("fit the model first")
        return predict(data, self.terms, self.fit_.values)

    def score(self, data: LoopData, held: np.ndarray | None = None) -> float:
        """RMSE of the fitted model on `data` (on the held-out samples when `held` is given)."""
        e = (data.measured - self.predict(data))[data.in_range if held is None else held & data.in_range]
        return float(np.sqrt(np.mean(e ** 2)))

    def parameters(self) -> dict:
        if self.fit_ is None:
            raise ValueError("fit the model first")
        return self.fit_.parameters()


def evaluate(data: LoopData, terms: list[Term], values: Values, held: np.ndarray) -> Fit:
    """A Fit of `terms` at given `values` (nothing fitted): the declared model as given."""
    model = EffectModel(terms, fixed=values).fit(data, held)
    return model.fit_
