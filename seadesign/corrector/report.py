"""Result tables (CSV, Markdown, JSON) and plots of the corrector evaluation.

Column units are in the names; `UNITS` spells them out and is printed under every Markdown table.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

UNITS = (("_norm_pi2", "(rad/pi)^2, the thesis's normalised positions"), ("_rad2", "rad^2"), ("_rad", "rad"),
         ("_pct", "%"), ("_s", "s"), ("_hz", "Hz"), ("_flag", "true/false"), ("n_", "count"),
         ("modulus_margin", "1, min over frequency of |1 + L| (L: loop gain)"),
         ("crossover_gain", "1, |L| where L crosses the negative real axis (1 / gain margin)"),
         ("loop_gain_peak", "1, max |L|"), ("margin_coherence", "1, coherence of L at the margin's frequency"))


def unit_of_column(name: str) -> str | None:
    """Unit of a table column from its name, None for label columns."""
    for key, unit in UNITS:
        if name.endswith(key) or (key.endswith("_") and name.startswith(key)):
            return unit
    return None


def _unit_line(columns: list[str]) -> str:
    parts = [f"`{c}` {u}" for c in columns if (u := unit_of_column(c))]
    return "Units: " + "; ".join(parts) + "." if parts else ""


def markdown(df: pd.DataFrame, floatfmt: str = ".4g") -> str:
    """A GitHub Markdown table of `df` with a units line."""
    def cell(v: Any) -> str:
        if isinstance(v, (float, np.floating)):
            return format(float(v), floatfmt)
        return str(v)

    head = "| " + " | ".join(df.columns) + " |"
    rule = "|" + "|".join("---" for _ in df.columns) + "|"
    rows = ["| " + " | ".join(cell(v) for v in row) + " |" for row in df.itertuples(index=False)]
    return "\n".join([head, rule, *rows, "", _unit_line(list(df.columns)), ""])


def write_table(df: pd.DataFrame, out_dir: str | Path, stem: str, context: dict | None = None) -> dict[str, Path]:
    """Write `stem`.csv and `stem`.md (with `context` as a settings block) into `out_dir`."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    csv, md = out / f"{stem}.csv", out / f"{stem}.md"
    df.to_csv(csv, index=False)
    text = markdown(df)
    if context:
        text += "\nSettings:\n\n```json\n" + json.dumps(context, indent=2, default=str) + "\n```\n"
    md.write_text(text)
    return {"csv": csv, "md": md}


def plot_predictions(traces: dict[str, dict], out_path: str | Path, knee: int = 0, n_steps: int = 400) -> Path:
    """Prediction (blue) vs the recorded task output (red) over the same held-out steps, one panel per
    candidate (as thesis figs. 6.5 / C.1). Uses the first contiguous run of `knee` (0 left, 1 right)."""
    first = next(iter(traces.values()))
    sel = np.flatnonzero(first["knee"] == knee)
    if len(sel) == 0:
        sel = np.arange(len(first["knee"]))
    rec, step = first["recording"][sel], first["step"][sel]
    breaks = np.flatnonzero((np.diff(step) != 1) | (np.diff(rec) != 0))
    end = breaks[0] + 1 if len(breaks) else len(sel)
    sel = sel[: min(end, n_steps)]
    fig, axes = plt.subplots(len(traces), 1, figsize=(9, 1.8 * len(traces)), sharex=True, squeeze=False)
    for ax, (name, tr) in zip(axes[:, 0], traces.items()):
        ax.plot(tr["truth"][sel], color="red", lw=1.2, label="recorded (task output)")
        ax.plot(tr["pred"][sel], color="blue", lw=1.0, label="command")
        ax.set_ylabel("rad")
        ax.set_title(name, fontsize=9, loc="left")
    axes[0, 0].legend(fontsize=7, loc="upper right")
    axes[-1, 0].set_xlabel(f"held-out step ({'left' if knee == 0 else 'right'} knee)")
    fig.tight_layout()
    fig.savefig(out_path, dpi=110)
    plt.close(fig)
    return Path(out_path)


#: validation scores of training curves: column -> axis label
CURVE_SCORES = {"val_mse_rad2": "validation MSE (rad^2)",
                "val_mean_abs_error_rad": "closed-loop validation mean |Hall error| (rad)"}


def plot_curves(curves: dict[str, list[dict]], out_path: str | Path) -> Path:
    """Validation score per epoch for each trained candidate, one panel per score: the MSE (rad^2) of networks
    trained on labels or recordings, the closed-loop mean |Hall error| (rad) of those trained through the loop."""
    used = [c for c in CURVE_SCORES if any(curve and c in curve[0] for curve in curves.values())] or list(CURVE_SCORES)[:1]
    fig, axes = plt.subplots(1, len(used), figsize=(7 * len(used), 4), squeeze=False)
    for ax, score in zip(axes[0], used):
        for name, curve in curves.items():
            if curve and score in curve[0]:
                ax.semilogy([r["epoch"] for r in curve], [r[score] for r in curve], label=name)
        ax.set_xlabel("epoch")
        ax.set_ylabel(CURVE_SCORES[score])
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(out_path, dpi=110)
    plt.close(fig)
    return Path(out_path)
