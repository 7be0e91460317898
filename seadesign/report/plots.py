"""Matplotlib figures of a ranked sweep (PNG): thesis fig. 5.3 analogue, k vs beam count, Pareto front."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

from seadesign.sweep.rank import ACCURACY, PROTECTION  # noqa: E402


def _by_thickness(t: pd.DataFrame):
    solved = t[t["status"] == "ok"]
    for thickness, group in solved.groupby("beam_thickness_mm"):
        yield thickness, group.sort_values("beam_count")


def _series_with_fit(ax, x: np.ndarray, y: np.ndarray, label: str, log: bool, color) -> None:
    """Points and a least-squares line (exponential fit, a line on a log axis, when `log`)."""
    ax.plot(x, y, "o", color=color, label=label)
    if len(x) >= 2:
        xs = np.linspace(x.min(), x.max(), 50)
        if log and np.all(y > 0):
            c = np.polyfit(x, np.log(y), 1)
            ax.plot(xs, np.exp(np.polyval(c, xs)), "-", color=color, alpha=0.7)
        else:
            c = np.polyfit(x, y, 1)
            ax.plot(xs, np.polyval(c, xs), "-", color=color, alpha=0.7)


def fig_reaction_displacement(t: pd.DataFrame, path: Path) -> Path:
    """Thesis fig. 5.3 analogue: impact reaction per hub bolt and stall displacement vs beam count."""
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(10, 4))
    for i, (thickness, g) in enumerate(_by_thickness(t)):
        color = f"C{i}"
        n = g["beam_count"].to_numpy(float)
        _series_with_fit(a1, n, g["impact_reaction_per_bolt_N"].to_numpy(float), f"{thickness:g} mm", False, color)
        _series_with_fit(a2, n, g[ACCURACY].to_numpy(float), f"{thickness:g} mm", True, color)
    thesis = t.dropna(subset=["thesis_reaction_N"])
    if len(thesis):
        a1.plot(thesis["beam_count"], thesis["thesis_reaction_N"], "k*", ms=10, label="thesis (NASTRAN)")
        a2.plot(thesis["beam_count"], thesis["thesis_displacement_mm"], "k*", ms=10, label="thesis (NASTRAN)")
    a1.set(xlabel="beam count (-)", ylabel="impact reaction per hub bolt (N)", title="Reaction force (impact)")
    a2.set(xlabel="beam count (-)", ylabel="stall bearing displacement (mm)", title="Displacement (stall)", yscale="log")
    for a in (a1, a2):
        a.legend(title="beam thickness")
        a.grid(alpha=0.3)
    fig.suptitle("Lines: linear fit (reaction) and exponential fit (displacement) per thickness")
    return _save(fig, path)


def fig_k(t: pd.DataFrame, path: Path) -> Path:
    """k vs beam count per thickness, error bars from the P1/P2 estimate, the k range if set."""
    fig, ax = plt.subplots(figsize=(6, 4))
    for i, (thickness, g) in enumerate(_by_thickness(t)):
        k = g["k_Nm_per_rad"].to_numpy(float)
        ax.errorbar(g["beam_count"], k, yerr=k * g["k_rel_error"].to_numpy(float), fmt="o-", capsize=3,
                    color=f"C{i}", label=f"{thickness:g} mm")
    ax.set(xlabel="beam count (-)", ylabel="k (Nm/rad)", yscale="log", title="Torsional stiffness (bars: P1-P2 difference)")
    ax.grid(alpha=0.3, which="both")
    ax.legend(title="beam thickness")
    return _save(fig, path)


def fig_pareto(t: pd.DataFrame, chosen: int | None, path: Path) -> Path:
    """Accuracy vs protection objective of every solved candidate; front, pool and choice marked."""
    fig, ax = plt.subplots(figsize=(6, 4.5))
    solved = t[t["status"] == "ok"]
    pool = solved[solved["score"].notna()]
    ax.plot(solved[ACCURACY], solved[PROTECTION], "o", color="0.7", label="solved, not in the pool")
    ax.plot(pool[ACCURACY], pool[PROTECTION], "o", color="C0", label="pool (feasible, or fewest violations)")
    front = pool[pool["pareto"]].sort_values(ACCURACY)
    ax.plot(front[ACCURACY], front[PROTECTION], "-", color="C0", alpha=0.6, label="Pareto front")
    for _, r in solved.iterrows():
        ax.annotate(f"{r['beam_count']}/{r['beam_thickness_mm']:g}", (r[ACCURACY], r[PROTECTION]), fontsize=7,
                    xytext=(3, 3), textcoords="offset points")
    if chosen is not None:
        c = t.loc[chosen]
        ax.plot(c[ACCURACY], c[PROTECTION], "r*", ms=16, label=f"chosen: {c['candidate']}")
    ax.set(xlabel="stall bearing displacement (mm), lower = more accurate",
           ylabel="peak impact torque into gearbox (Nm)", xscale="log", title="Accuracy vs gearbox protection")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=7)
    return _save(fig, path)


def _save(fig, path: Path) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
