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


def split_metrics(measured: np.ndarray, predicted: np.ndarray, held: np.ndarray) -> dict[str, dict[str, float]]:
    """Metrics on the training part (~held) and the held-out part (held)."""
    return {"train": metrics(measured[~held], predicted[~held]), "held_out": metrics(measured[held], predicted[held])}
