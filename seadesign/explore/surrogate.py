"""Surrogates: a Gaussian process per output, and a classifier of where designs can be built.

`Surrogate` follows scikit-learn's fit / predict / score. Each output is modelled on the unit-cube
coordinates of the designs solved so far (`encoding.py`) with a constant x anisotropic Matern-5/2
kernel plus a small white-noise term (the FEA is deterministic but not smooth to round-off:
remeshing moves an output by a fraction of its discretization error), the targets standardised;
an output that is positive everywhere (a stiffness, a mass, a torque) is modelled in log space,
so a relative error is what the kernel sees and predictions stay positive.

Leave-one-out error: each solved design predicted by the process conditioned on all the others,
with the hyperparameters fitted on all (the closed form of Rasmussen & Williams eq. 5.12:
residual_i = [K^-1 y]_i / [K^-1]_ii), reported as the mean absolute relative error and the
largest one.

`FeasibilityClassifier` learns where geometry is valid (and the pipeline solves it) from every
design screened, valid or not: a Gaussian-process classifier giving P(valid) at any point. Invalid
geometry is thus a boundary in the design space, not a crash.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass

import numpy as np
from scipy.linalg import cho_solve

NOISE_BOUNDS = (1e-8, 1e-1)  # white noise on the standardised target: round-off up to 30 % of its scatter
LENGTH_BOUNDS = (1e-2, 1e2)  # kernel length scales in unit-cube coordinates
RESTARTS = 4  # extra starts of the hyperparameter fit (seeded)
MIN_POINTS = 3  # fewer data than this: the output has no surrogate (predicted as unknown)


def _kernel(dim: int):
    from sklearn.gaussian_process.kernels import ConstantKernel, Matern, WhiteKernel

    return (ConstantKernel(1.0, (1e-3, 1e3)) * Matern(np.ones(dim), LENGTH_BOUNDS, nu=2.5)
            + WhiteKernel(1e-4, NOISE_BOUNDS))


@dataclass(frozen=True)
class LooError:
    """Leave-one-out error of one output over the designs it was fitted on."""

    n: int
    mean_abs_rel: float  # mean |predicted - solved| / |solved| (NaN: fewer than MIN_POINTS + 1 designs)
    max_abs_rel: float
    rmse: float  # in the output's unit


class Surrogate:
    """A Gaussian process of one output over unit-cube coordinates (scikit-learn style)."""

    def __init__(self, log: bool = False, seed: int = 0) -> None:
        self.log, self.seed = log, seed
        self.gp = None
        self.constant: float | None = None  # fewer than MIN_POINTS data: no model

    def fit(self, X: np.ndarray, y: np.ndarray) -> "Surrogate":
        """Fit on the finite entries of y (X: (n, dim) in [0, 1])."""
        from sklearn.gaussian_process import GaussianProcessRegressor

        X, y = np.asarray(X, float), np.asarray(y, float)
        keep = np.isfinite(y)
        X, y = X[keep], y[keep]
        self.X_, self.y_ = X, y
        self.log_ = self.log and len(y) > 0 and bool(np.all(y > 0))
        if len(y) < MIN_POINTS:
            self.gp, self.constant = None, float(np.mean(y)) if len(y) else math.nan
            return self
        self.gp = GaussianProcessRegressor(_kernel(X.shape[1]), normalize_y=True, n_restarts_optimizer=RESTARTS,
                                           random_state=self.seed)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # convergence notes at the length-scale bounds
            self.gp.fit(X, self._forward(y))
        return self

    def _forward(self, y: np.ndarray) -> np.ndarray:
        return np.log(y) if self.log_ else y

    def predict(self, X: np.ndarray, return_std: bool = False):
        """Mean (and standard deviation) at X, in the output's unit. A log-space model returns the
        median exp(mu) and the delta-method standard deviation exp(mu) sigma."""
        X = np.atleast_2d(np.asarray(X, float))
        if self.gp is None:
            mean = np.full(len(X), self.constant)
            return (mean, np.full(len(X), np.inf)) if return_std else mean
        mu, sd = self.gp.predict(X, return_std=True)
        if self.log_:
            mu = np.exp(mu)
            sd = mu * sd
        return (mu, sd) if return_std else mu

    def loo(self) -> np.ndarray:
        """Leave-one-out predictions at the fitted designs (hyperparameters fixed; see the module doc)."""
        if self.gp is None:
            return np.full(len(self.y_), math.nan)
        gp = self.gp
        K_inv = cho_solve((gp.L_, True), np.eye(len(self.y_)))
        alpha = gp.alpha_.ravel()  # K^-1 y in standardised units
        loo_std = self._forward(self.y_) - alpha / np.diag(K_inv) * float(np.ravel(gp._y_train_std)[0])  # noqa: SLF001
        return np.exp(loo_std) if self.log_ else loo_std

    def loo_error(self) -> LooError:
        y = self.y_
        if self.gp is None or len(y) <= MIN_POINTS:
            return LooError(len(y), math.nan, math.nan, math.nan)
        pred = self.loo()
        rel = np.abs(pred - y) / np.maximum(np.abs(y), 1e-12)
        return LooError(len(y), float(rel.mean()), float(rel.max()), float(np.sqrt(np.mean((pred - y) ** 2))))

    def score(self, X: np.ndarray, y: np.ndarray) -> float:
        """Coefficient of determination R^2 on (X, y), as scikit-learn's regressors."""
        y = np.asarray(y, float)
        resid = y - self.predict(X)
        return float(1.0 - np.sum(resid**2) / np.sum((y - y.mean()) ** 2))


class FeasibilityClassifier:
    """P(the design can be built and solved) from screened designs (scikit-learn style)."""

    def __init__(self, seed: int = 0) -> None:
        self.seed = seed
        self.model = None
        self.constant = 1.0

    def fit(self, X: np.ndarray, valid: np.ndarray) -> "FeasibilityClassifier":
        from sklearn.gaussian_process import GaussianProcessClassifier
        from sklearn.gaussian_process.kernels import ConstantKernel, Matern

        valid = np.asarray(valid, bool)
        if len(valid) == 0 or valid.all() or not valid.any():
            self.model, self.constant = None, float(valid.all()) if len(valid) else 1.0
            return self
        kernel = ConstantKernel(1.0, (1e-2, 1e3)) * Matern(np.ones(np.shape(X)[1]), LENGTH_BOUNDS, nu=2.5)
        self.model = GaussianProcessClassifier(kernel, n_restarts_optimizer=RESTARTS, random_state=self.seed)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            self.model.fit(np.asarray(X, float), valid)
        return self

    def predict_proba(self, X: np.ndarray) -> np.ndarray:
        """P(valid) at each row of X."""
        X = np.atleast_2d(np.asarray(X, float))
        if self.model is None:
            return np.full(len(X), self.constant)
        return self.model.predict_proba(X)[:, list(self.model.classes_).index(True)]
