"""Fitting a model (the prediction plus a list of candidate effects) by bounded least squares.

All parameters of all effects in the model are fitted together on the training samples
(`scipy.optimize.least_squares`, trust-region reflective with bounds; positive scale
parameters such as time constants are searched in log space). The model is always evaluated
over the whole record (stateful effects need the history), but the optimiser sees at most
`MAX_FIT_ROWS` evenly spaced training samples, which keeps its linear algebra small on long
recordings; errors and information criteria use every training sample, and the Jacobian is
rescaled to the full count for the uncertainties. Uncertainty is the
standard error from the Jacobian, cov = s^2 (J^T J)^-1 with s^2 = SSR / (n - p); residuals of
real recordings are correlated, so these are lower bounds. Information criteria use the
Gaussian likelihood on all training samples: AIC = n ln(SSR/n) + 2p, BIC = n ln(SSR/n) + p ln n.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from itertools import product
from typing import Sequence

import numpy as np
from scipy.optimize import least_squares

from seadesign.effects import Param
from seadesign.loop.candidates import LIBRARY, LOAD_STAGE, Candidate
from seadesign.loop.metrics import split_metrics
from seadesign.loop.table import LoopData

MAX_FIT_ROWS = 8000


def order(keys: Sequence[str]) -> list[Candidate]:
    """Candidates of `keys` in the order they act (torque path first, delay last)."""
    return sorted((LIBRARY[k] for k in keys), key=lambda c: c.stage)


def predict(data: LoopData, keys: Sequence[str], theta: Sequence[float]) -> np.ndarray:
    """The prediction with the effects `keys` applied with parameters `theta` (concatenated in key order)."""
    values = _split(data, keys, theta)
    path = data.path
    rest = data.predicted - data.path
    y = None
    for cand in order(keys):
        if cand.stage >= LOAD_STAGE and y is None:
            y = rest + path
        if cand.stage < LOAD_STAGE:
            path = cand.apply(data, values[cand.key], path)
        else:
            y = cand.apply(data, values[cand.key], y)
    return rest + path if y is None else y


def _split(data: LoopData, keys: Sequence[str], theta: Sequence[float]) -> dict[str, np.ndarray]:
    out, i = {}, 0
    for k in keys:
        m = len(LIBRARY[k].params(data))
        out[k] = np.asarray(theta[i:i + m], dtype=float)
        i += m
    return out


@dataclass
class Fit:
    """A fitted model: effect keys, parameters (value, uncertainty, unit) and its scores."""

    keys: tuple[str, ...]
    theta: np.ndarray
    sigma: np.ndarray
    params: list[tuple[str, Param]]
    prediction: np.ndarray
    errors: dict[str, dict[str, float]]
    aic: float
    bic: float
    n_train: int
    extra: dict = field(default_factory=dict)

    def parameters(self) -> dict[str, dict[str, dict[str, float | str]]]:
        """effect -> parameter -> {value, uncertainty, unit, meaning, at_bound} (at_bound: the fit hit a
        search bound, so the value is a limit, not an estimate)."""
        out: dict = {}
        for (key, p), v, s in zip(self.params, self.theta, self.sigma):
            at_bound = bool(np.isclose(v, p.lower, rtol=1e-6, atol=0) or np.isclose(v, p.upper, rtol=1e-6, atol=0))
            out.setdefault(key, {})[p.name] = {"value": float(v), "uncertainty": float(s), "unit": p.unit,
                                               "meaning": p.doc, "at_bound": at_bound}
        return out


def _scores(ssr: float, n: int, p: int) -> tuple[float, float]:
    ll = n * np.log(max(ssr, 1e-300) / n)
    return float(ll + 2 * p), float(ll + p * np.log(n))


def fit(data: LoopData, keys: Sequence[str], held: np.ndarray,
        warm: dict[str, np.ndarray] | None = None) -> Fit:
    """Fit all parameters of `keys` on the training samples (~held); `warm` gives start values per effect.

    Effects without a warm start try each of their start points (all combinations); the best
    training cost wins.
    """
    keys = tuple(keys)
    train = ~held
    params = [(k, p) for k in keys for p in LIBRARY[k].params(data)]
    lo = np.array([p.lower for _, p in params])
    hi = np.array([p.upper for _, p in params])
    logs = np.zeros(len(params), bool)
    i = 0
    for k in keys:
        c = LIBRARY[k]
        logs[[i + j for j in c.log]] = True
        i += len(c.params(data))
    to_u = lambda x: np.where(logs, np.log(np.where(logs, x, 1.0)), x)  # noqa: E731
    to_x = lambda u: np.where(logs, np.exp(np.where(logs, u, 0.0)), u)  # noqa: E731
    ulo, uhi = to_u(lo), to_u(hi)
    if not keys:
        pred = data.predicted
        ssr = float(np.sum((data.measured[train] - pred[train]) ** 2))
        aic, bic = _scores(ssr, int(train.sum()), 0)
        return Fit(keys, np.zeros(0), np.zeros(0), [], pred, split_metrics(data.measured, pred, held), aic, bic,
                   int(train.sum()))
    warm = warm or {}
    options = [[list(warm[k])] if k in warm else LIBRARY[k].starts(data) for k in keys]
    n = int(train.sum())
    rows = np.flatnonzero(train)[:: max(1, -(-n // MAX_FIT_ROWS))]
    y = data.measured[rows]

    def resid(u):
        return predict(data, keys, np.clip(to_x(u), lo, hi))[rows] - y

    best = None
    for combo in product(*options):
        u0 = to_u(np.clip(np.concatenate([np.asarray(c, float) for c in combo]), lo, hi))
        u0 = np.clip(u0, ulo + 1e-9 * (uhi - ulo), uhi - 1e-9 * (uhi - ulo))
        res = least_squares(resid, u0, bounds=(ulo, uhi), x_scale="jac", method="trf", max_nfev=100 * len(u0))
        if best is None or res.cost < best.cost:
            best = res
    p = len(params)
    x = np.clip(to_x(best.x), lo, hi)
    pred = predict(data, keys, x)
    ssr = float(np.sum((data.measured[train] - pred[train]) ** 2))
    jac = best.jac * np.where(logs, 1.0 / x, 1.0)  # chain rule: d/dx = d/du / x for log parameters
    try:
        cov = np.linalg.pinv(jac.T @ jac * (n / rows.size)) * ssr / max(n - p, 1)
        sigma = np.sqrt(np.clip(np.diag(cov), 0, None))
    except np.linalg.LinAlgError:
        sigma = np.full(p, np.nan)
    aic, bic = _scores(ssr, n, p)
    return Fit(keys, x, sigma, params, pred, split_metrics(data.measured, pred, held), aic, bic, n)


def warm_starts(f: Fit, data: LoopData) -> dict[str, np.ndarray]:
    """Per-effect parameter vectors of a fit, to start the next fit from."""
    return _split(data, f.keys, f.theta)
