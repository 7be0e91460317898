"""Matplotlib figures of an exploration (PNG): Sobol indices, parallel coordinates of the evaluated designs
coloured by feasibility, how the search went, and the surrogates' leave-one-out predictions."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

from seadesign.design.space import axis_label  # noqa: E402
from seadesign.report.plots import _save  # noqa: E402

# how a results column reads on a plot axis (with its unit)
COLUMN_LABELS = {
    "k_Nm_per_rad": "k at rest (Nm/rad)", "mass_g": "mass (g)", "large_stall_rotation_rad": "rotation at stall (rad)",
    "large_stop_torque_Nm": "path ends at (Nm)", "usable_torque_Nm": "usable torque (Nm)",
    "standing_deflection_deg": "standing sag (deg)", "large_stall_bearing_displacement_mm": "stall bearing arc (mm)",
    "impact_gearbox_torque_Nm": "strike torque (Nm)", "total_violation": "total miss (-)",
}


def column_label(column: str) -> str:
    return COLUMN_LABELS.get(column, axis_label(column))


def fig_sobol(indices: pd.DataFrame, path: Path) -> Path:
    """Total Sobol index (bars, 95 % interval) and first-order index (dots) of each output to each axis."""
    outputs = list(dict.fromkeys(indices["output"]))
    axes = list(dict.fromkeys(indices["axis"]))
    fig, ax = plt.subplots(figsize=(max(6.0, 1.3 * len(outputs) * max(1, len(axes)) / 3), 4.2))
    width = 0.8 / max(len(axes), 1)
    for j, axis in enumerate(axes):
        sub = indices[indices["axis"] == axis].set_index("output").reindex(outputs)
        x = np.arange(len(outputs)) + (j - (len(axes) - 1) / 2) * width
        ax.bar(x, sub["ST"].clip(lower=0), width, yerr=sub["ST_conf"], capsize=2, color=f"C{j}", label=axis_label(axis))
        ax.plot(x, sub["S1"].clip(lower=0), "k.", ms=5)
    ax.set_xticks(np.arange(len(outputs)), [column_label(o) for o in outputs], rotation=20, ha="right", fontsize=8)
    ax.set(ylabel="Sobol index (-)", ylim=(0, 1.05), title="Sensitivity on the surrogates (bars: total, dots: first order)")
    ax.legend(fontsize=7, ncol=min(len(axes), 4))
    ax.grid(alpha=0.3, axis="y")
    return _save(fig, path)


def fig_parallel(evaluated: pd.DataFrame, invalid: pd.DataFrame, axes: list[str], columns: list[str],
                 chosen, path: Path) -> Path:
    """Each design a line through its axis values and outputs (each scaled to its range, labels with the range;
    a categorical axis, such as the material, has its categories as ticks, evenly spaced): feasible green,
    conditional blue, infeasible orange, invalid geometry grey (screened only), the choice red."""
    cols = [*axes, *columns]
    conditional = evaluated["conditional"].astype(bool) if "conditional" in evaluated else False
    kinds = np.where(evaluated["feasible"], "feasible", np.where(conditional, "conditional", "infeasible"))
    frame = pd.concat([evaluated.assign(_kind=kinds), invalid.assign(_kind="invalid geometry")], ignore_index=True)
    categories = {c: sorted(frame[c].dropna().unique()) for c in cols if not pd.api.types.is_numeric_dtype(frame[c])}
    numeric = pd.DataFrame({c: frame[c].map({v: float(i) for i, v in enumerate(categories[c])}) if c in categories
                            else pd.to_numeric(frame[c], errors="coerce") for c in cols})
    lo, hi = numeric.min(), numeric.max()
    scaled = (numeric - lo) / (hi - lo).replace(0, 1)
    fig, ax = plt.subplots(figsize=(max(7.0, 1.1 * len(cols)), 4.4))
    colours = {"invalid geometry": ("0.75", 0.6), "infeasible": ("C1", 0.8), "conditional": ("C0", 0.9),
               "feasible": ("C2", 1.0)}
    for kind, (colour, alpha) in colours.items():
        rows = scaled[frame["_kind"] == kind]
        for i, (_, r) in enumerate(rows.iterrows()):
            ax.plot(range(len(cols)), r.to_numpy(float), "-", color=colour, alpha=alpha, lw=0.9,
                    label=kind if i == 0 else None)
    if chosen is not None:
        ax.plot(range(len(cols)), scaled.iloc[int(np.flatnonzero(evaluated.index == chosen)[0])].to_numpy(float), "-",
                color="r", lw=2.5, label="choice")
    for j, c in enumerate(cols):  # a categorical axis: its categories as ticks where the lines pass
        for i, name in enumerate(categories.get(c, ())):
            y = (i - lo[c]) / ((hi[c] - lo[c]) or 1)
            ax.plot([j - 0.04, j + 0.04], [y, y], "k-", lw=1.2)
            ax.annotate(str(name), (j, y), xytext=(4, 2), textcoords="offset points", fontsize=7)
    labels = [f"{column_label(c)}\n" + ("categories" if c in categories else f"{lo[c]:.3g}-{hi[c]:.3g}")
              for c in cols]
    ax.set_xticks(range(len(cols)), labels, fontsize=7, rotation=25, ha="right")
    ax.set(yticks=[], title="Evaluated designs (each column scaled to its range)")
    ax.legend(fontsize=7, loc="upper right")
    ax.grid(alpha=0.3, axis="x")
    return _save(fig, path)


def fig_history(rounds, objective: str, path: Path) -> Path:
    """Best feasible first objective and least total violation against full evaluations."""
    n = [r.evaluations for r in rounds]
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(9, 3.6))
    a1.plot(n, [r.best_objective for r in rounds], "o-")
    a1.set(xlabel="full-path evaluations", ylabel=column_label(objective), title="Best feasible design")
    a2.plot(n, [r.least_violation for r in rounds], "o-", color="C1")
    a2.set(xlabel="full-path evaluations", ylabel="least total miss (-)", title="Least total violation")
    for a in (a1, a2):
        a.grid(alpha=0.3)
    return _save(fig, path)


def fig_loo(models, outputs: list[str], path: Path) -> Path:
    """Leave-one-out prediction against the solved value for each output, with its mean relative error."""
    shown = [o for o in outputs if models.surrogates[o].gp is not None]
    fig, axs = plt.subplots(1, max(len(shown), 1), figsize=(2.7 * max(len(shown), 1), 2.9), squeeze=False)
    for ax, o in zip(axs[0], shown):
        s = models.surrogates[o]
        y, p = s.y_, s.loo()
        ax.plot(y, p, "o", ms=4)
        lim = [min(y.min(), p.min()), max(y.max(), p.max())]
        ax.plot(lim, lim, "k-", lw=0.8)
        ax.set_title(f"{column_label(o)}\nLOO error {s.loo_error().mean_abs_rel:.1%}", fontsize=8)
        ax.set_xlabel("solved", fontsize=8)
        ax.tick_params(labelsize=7)
    axs[0][0].set_ylabel("predicted without it", fontsize=8)
    return _save(fig, path)
