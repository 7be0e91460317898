"""Error metrics of a residual (measured - predicted), in the measured quantity's unit."""

from __future__ import annotations

import numpy as np


def metrics(measured: np.ndarray, predicted: np.ndarray) -> dict[str, float]:
    """RMSE, peak |error|, mean error (bias) and fit % = 100 (1 - |e| / |y - mean y|); NaN for no samples."""
    if measured.size == 0:
        return dict.fromkeys(("rmse", "peak", "bias", "fit_percent"), float("nan"))
    e = measured - predicted
    spread = np.linalg.norm(measured - measured.mean())
    return {
        "rmse": float(np.sqrt(np.mean(e * e))),
        "peak": float(np.max(np.abs(e))),
        "bias": float(np.mean(e)),
        "fit_percent": float(100.0 * (1.0 - np.linalg.norm(e) / spread)) if spread > 0 else float("nan"),
    }


def split_metrics(measured: np.ndarray, predicted: np.ndarray, held: np.ndarray,
                  used: np.ndarray | None = None) -> dict[str, dict[str, float]]:
    """Metrics on the training part (~held) and the held-out part (held), of the samples `used` (all when None)."""
    used = np.ones(measured.size, bool) if used is None else used
    train, test = ~held & used, held & used
    return {"train": metrics(measured[train], predicted[train]), "held_out": metrics(measured[test], predicted[test])}
