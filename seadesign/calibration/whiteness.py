"""Residual whiteness: Ljung-Box autocorrelation test, cross-correlation with each signal, and
how much of the residual a smooth function of each signal explains (where the structure is)."""

from __future__ import annotations

import numpy as np
from scipy import stats

#: p-value below which the residual is called structured (Ljung-Box).
ALPHA = 0.01
#: |correlation| above Z / sqrt(n) is called significant (under a white residual the
#: sample cross-correlation has standard deviation 1 / sqrt(n)).
Z = 4.0


def _acf(x: np.ndarray, max_lag: int) -> np.ndarray:
    x = x - x.mean()
    n = x.size
    f = np.fft.rfft(x, 2 * n)
    r = np.fft.irfft(f * np.conj(f))[: max_lag + 1]
    return r / r[0] if r[0] > 0 else np.zeros(max_lag + 1)


def _xcorr(r: np.ndarray, s: np.ndarray, max_lag: int) -> tuple[np.ndarray, np.ndarray]:
    """corr(r_t, s_{t-lag}) for lag in [-max_lag, max_lag]: positive lag = residual follows the signal."""
    r, s = r - r.mean(), s - s.mean()
    n = r.size
    denom = np.sqrt((r @ r) * (s @ s))
    full = np.fft.irfft(np.fft.rfft(r, 2 * n) * np.conj(np.fft.rfft(s, 2 * n)), 2 * n)
    lags = np.arange(-max_lag, max_lag + 1)
    vals = full[lags % (2 * n)] / denom if denom > 0 else np.zeros(lags.size)
    return lags, vals


def binned_share(residual: np.ndarray, signal: np.ndarray, bins: int = 20) -> float:
    """Share of residual variance explained by its mean in `bins` quantile bins of `signal` (0..1)."""
    edges = np.unique(np.quantile(signal, np.linspace(0, 1, bins + 1)))
    if edges.size < 3:
        return 0.0
    idx = np.clip(np.searchsorted(edges, signal, side="right") - 1, 0, edges.size - 2)
    count = np.bincount(idx, minlength=edges.size - 1)
    means = np.bincount(idx, weights=residual, minlength=edges.size - 1) / np.maximum(count, 1)
    total = np.sum((residual - residual.mean()) ** 2)
    explained = np.sum(count * (means - residual.mean()) ** 2)
    # remove the share pure noise would explain by chance (bins - 1 degrees of freedom)
    chance = (edges.size - 2) / residual.size
    return float(max(explained / total - chance, 0.0)) if total > 0 else 0.0


def residual_tests(residual: np.ndarray, time: np.ndarray, signals: dict[str, np.ndarray],
                   max_lag_s: float = 2.0) -> dict:
    """Ljung-Box on the residual's autocorrelation and per-signal structure.

    Lags are reported in samples and seconds (median sample interval). Returns a JSON-ready dict
    with `white` (no test finds structure) and `strongest` (signal and lag of the largest structure).
    """
    n = residual.size
    dt = float(np.median(np.diff(time)))
    max_lag = int(max(5, min(n // 5, round(max_lag_s / dt))))
    rho = _acf(residual, max_lag)[1:]
    lags = np.arange(1, max_lag + 1)
    q = float(n * (n + 2) * np.sum(rho**2 / (n - lags)))
    p = float(stats.chi2.sf(q, max_lag))
    k = int(np.argmax(np.abs(rho)))
    auto = {"test": "Ljung-Box", "lags": max_lag, "Q": q, "p_value": p, "structured": p < ALPHA,
            "strongest_lag_samples": int(lags[k]), "strongest_lag_s": float(lags[k] * dt),
            "strongest_autocorrelation": float(rho[k])}
    threshold = Z / np.sqrt(n)
    cross = {}
    for role, s in signals.items():
        if np.ptp(s) == 0:
            continue
        xl, xv = _xcorr(residual, s, max_lag)
        j = int(np.argmax(np.abs(xv)))
        share = binned_share(residual, s)
        cross[role] = {"max_abs_correlation": float(abs(xv[j])), "lag_samples": int(xl[j]),
                       "lag_s": float(xl[j] * dt), "threshold": float(threshold),
                       "explained_share_binned": share,
                       "structured": bool(abs(xv[j]) > threshold or share > 0.05)}
    structured = [r for r, c in cross.items() if c["structured"]]
    if structured:
        top = max(structured, key=lambda r: max(cross[r]["max_abs_correlation"], cross[r]["explained_share_binned"]))
        strongest = {"signal": top, "lag_s": cross[top]["lag_s"],
                     "correlation": cross[top]["max_abs_correlation"],
                     "explained_share_binned": cross[top]["explained_share_binned"]}
    elif auto["structured"]:
        strongest = {"signal": "residual itself (autocorrelation)", "lag_s": auto["strongest_lag_s"],
                     "correlation": auto["strongest_autocorrelation"], "explained_share_binned": 0.0}
    else:
        strongest = None
    return {"autocorrelation": auto, "cross": cross, "white": not auto["structured"] and not structured,
            "strongest": strongest}
