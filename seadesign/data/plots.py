"""The inspection plot of a recording: both knees with their artefacts marked, and sampling."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

from seadesign.data.artefacts import ArtefactReport, runs  # noqa: E402
from seadesign.data.robot import KNEE_SIGN, KNEES  # noqa: E402


def plot_recording(df: pd.DataFrame, report: ArtefactReport, path: str | Path) -> Path:
    """PNG: per knee motor and Hall (flexion convention) with steps, wraps, glitches and stuck
    segments marked, the deflection, and the sample interval with gaps."""
    t = df["time_s"].to_numpy(dtype=float)
    fig, axes = plt.subplots(5, 1, figsize=(14, 14), sharex=True)
    for i, side in enumerate(KNEES):
        s = KNEE_SIGN[side]
        motor, hall = s * df[f"{side}_knee_pos"].to_numpy(), s * df[f"{side}_hall_pos"].to_numpy()
        ax, axd = axes[2 * i], axes[2 * i + 1]
        ax.plot(t, motor, lw=0.8, label="motor (rad)")
        ax.plot(t, hall, lw=0.8, label="Hall (rad)")
        m = report.masks[side]
        for a, b in runs(m["stuck"]):
            ax.axvspan(t[a], t[b - 1], color="red", alpha=0.15, lw=0)
        for name, marker, color in (("step", "v", "red"), ("wrap", "^", "purple"), ("glitch", "x", "black")):
            idx = np.flatnonzero(m[name])
            if idx.size:
                ax.plot(t[idx], hall[idx], marker, color=color, ms=6, label=f"{name} ({idx.size})")
        ax.set_ylabel(f"{side} knee, flexion (rad)")
        ax.legend(loc="upper right", fontsize=7)
        axd.plot(t, motor - hall, lw=0.8, color="C2")
        offset = report.knees[side]["offset"]["first_rest_rad"]
        if offset is not None:
            axd.axhline(offset, color="k", ls="--", lw=0.8, label=f"offset at first rest {offset:.3f} rad")
            axd.legend(loc="upper right", fontsize=7)
        axd.set_ylabel(f"{side} deflection (rad)")
    dt = np.diff(t)
    axes[4].semilogy(t[1:], dt * 1e3, ".", ms=2)
    axes[4].axhline(report.sampling["gap_limit_s"] * 1e3, color="red", lw=0.8, label="gap limit")
    axes[4].set_ylabel("sample interval (ms)")
    axes[4].set_xlabel("time (s)")
    axes[4].legend(loc="upper right", fontsize=7)
    fig.suptitle(f"{report.source}: stuck Hall shaded red")
    fig.tight_layout()
    path = Path(path)
    fig.savefig(path, dpi=80)
    plt.close(fig)
    return path
