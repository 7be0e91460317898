"""Matplotlib figures of a ranked sweep (PNG): reaction and displacement (the thesis's fig. 5.3
where beam count and beam thickness are the axes), k, the Pareto front, and the large-deflection
torque curves.

The figures adapt to the study's design axes: the first axis is the x axis, and one series is
drawn per value of the other axes (per beam thickness in the default study).
"""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

from seadesign.design.space import axis_label, label  # noqa: E402
from seadesign.sweep.requirements import ACCURACY, PROTECTION  # noqa: E402

LEGEND_CURVES = 8  # torque curves named in a legend at most (an explorer's front holds dozens)
_NOT_RED = [f"C{i}" for i in range(10) if i != 3]  # the default colour cycle without its red, the choice's colour


def _series(t: pd.DataFrame, axes: list[str]):
    """(legend text, rows sorted by the first axis) per combination of the other axes' values."""
    solved = t[t["status"] == "ok"]
    x, others = axes[0], axes[1:]
    if not others:
        yield "", solved.sort_values(x)
        return
    for values, group in solved.groupby(others if len(others) > 1 else others[0]):
        values = values if isinstance(values, tuple) else (values,)
        yield ", ".join(label(k, v) for k, v in zip(others, values)), group.sort_values(x)


def _series_with_fit(ax, x: np.ndarray, y: np.ndarray, text: str, log: bool, color) -> None:
    """Points and a least-squares line (exponential fit, a line on a log axis, when `log`)."""
    ax.plot(x, y, "o", color=color, label=text or None)
    if len(x) >= 2:
        xs = np.linspace(x.min(), x.max(), 50)
        if log and np.all(y > 0):
            c = np.polyfit(x, np.log(y), 1)
            ax.plot(xs, np.exp(np.polyval(c, xs)), "-", color=color, alpha=0.7)
        else:
            c = np.polyfit(x, y, 1)
            ax.plot(xs, np.polyval(c, xs), "-", color=color, alpha=0.7)


def _legend(ax, axes: list[str]) -> None:
    if len(axes) > 1 or ax.get_legend_handles_labels()[0]:
        ax.legend(title=", ".join(axis_label(k) for k in axes[1:]) or None, fontsize=8)


def fig_reaction_displacement(t: pd.DataFrame, axes: list[str], path: Path) -> Path:
    """Impact reaction per hub bolt and stall displacement vs the first axis (thesis fig. 5.3
    analogue, with its NASTRAN points, when that axis is the beam count)."""
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(10, 4))
    x = axes[0]
    for i, (text, g) in enumerate(_series(t, axes)):
        n = g[x].to_numpy(float)
        _series_with_fit(a1, n, g["impact_reaction_per_bolt_N"].to_numpy(float), text, False, f"C{i}")
        _series_with_fit(a2, n, g[ACCURACY].to_numpy(float), text, True, f"C{i}")
    thesis = t.dropna(subset=["thesis_reaction_N"])
    if len(thesis) and x == "beam_count":
        a1.plot(thesis[x], thesis["thesis_reaction_N"], "k*", ms=10, label="thesis (NASTRAN)")
        a2.plot(thesis[x], thesis["thesis_displacement_mm"], "k*", ms=10, label="thesis (NASTRAN)")
    a1.set(xlabel=axis_label(x), ylabel="impact reaction per hub bolt (N)", title="Reaction force (impact)")
    a2.set(xlabel=axis_label(x), ylabel="stall bearing displacement (mm)", title="Displacement (stall)", yscale="log")
    for a in (a1, a2):
        _legend(a, axes)
        a.grid(alpha=0.3)
    fig.suptitle("Lines: linear fit (reaction) and exponential fit (displacement) per series")
    return _save(fig, path)


def fig_k(t: pd.DataFrame, axes: list[str], path: Path) -> Path:
    """k vs the first axis per series, error bars from the discretization-error estimate, the k range if set."""
    fig, ax = plt.subplots(figsize=(6, 4))
    x = axes[0]
    for i, (text, g) in enumerate(_series(t, axes)):
        k = g["k_Nm_per_rad"].to_numpy(float)
        ax.errorbar(g[x], k, yerr=k * g["k_rel_error"].to_numpy(float), fmt="o-", capsize=3, color=f"C{i}",
                    label=text or None)
    ax.set(xlabel=axis_label(x), ylabel="k (Nm/rad)", yscale="log",
           title="Torsional stiffness (bars: estimated discretization error)")
    ax.grid(alpha=0.3, which="both")
    _legend(ax, axes)
    return _save(fig, path)


def fig_pareto(t: pd.DataFrame, chosen: int | None, path: Path) -> Path:
    """Accuracy vs protection objective of every solved candidate; front, pool and choice marked."""
    fig, ax = plt.subplots(figsize=(6, 4.5))
    solved = t[t["status"] == "ok"]
    pool = solved[solved["rank"].notna()]
    ax.plot(solved[ACCURACY], solved[PROTECTION], "o", color="0.7", label="solved, not in the pool")
    ax.plot(pool[ACCURACY], pool[PROTECTION], "o", color="C0", label="pool (feasible, else conditional, else fewest misses)")
    front = pool[pool["pareto"]].sort_values(ACCURACY)
    ax.plot(front[ACCURACY], front[PROTECTION], "-", color="C0", alpha=0.6, label="Pareto front")
    for _, r in solved.iterrows():
        ax.annotate(r["candidate"], (r[ACCURACY], r[PROTECTION]), fontsize=6, xytext=(3, 3), textcoords="offset points")
    if chosen is not None:
        c = t.loc[chosen]
        ax.plot(c[ACCURACY], c[PROTECTION], "r*", ms=16, label=f"chosen: {c['candidate']}")
    ax.set(xlabel="stall bearing arc (mm, large deflection), lower = more accurate",
           ylabel="peak strike torque into gearbox (Nm)", xscale="log", title="Accuracy vs gearbox protection")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=7)
    return _save(fig, path)


END_MARKERS = {"limit_point": "^", "bifurcation": "v", "unconverged": "D", "target_reached": "|",
               "contact": "x"}  # where a curve ends, by reason (contact: a path without contact forces)


def fig_curves(t: pd.DataFrame, chosen: int | None, stall_Nm: float, impact_Nm: float, path: Path) -> Path:
    """Torque-rotation curves of the large-deflection paths: the Pareto candidates and the chosen one (the ranked
    pool when it could not be scored) in colour, the other solved ones in grey; each curve's end marked by its
    reason (`END_MARKERS`), first contact (x), where the tensile strain passes the cyclic (o) and the single-event
    limit (s), and the load torques. The legend names at most LEGEND_CURVES of the coloured curves: the chosen one,
    then the lightest."""
    fig, ax = plt.subplots(figsize=(7, 6.2))
    solved = t[t["status"] == "ok"]
    pareto = solved["pareto"].astype(bool)
    shown = solved[pareto | (solved.index == chosen)] if pareto.any() else solved[solved["rank"].notna()]
    for _, r in solved.drop(index=shown.index).iterrows():
        ax.plot(r["large_curve_rotation_rad"], r["large_curve_torque_Nm"], "-", color="0.8", lw=0.8)
    shown = shown.assign(_chosen=shown.index == chosen).sort_values(["_chosen", "mass_g"], ascending=[False, True],
                                                                    kind="stable")
    for i, (_, r) in enumerate(shown.iterrows()):
        color = "r" if r["_chosen"] else _NOT_RED[i % len(_NOT_RED)]
        named = i < LEGEND_CURVES
        ax.plot(r["large_curve_rotation_rad"], r["large_curve_torque_Nm"], "-", color=color, lw=1.6 if named else 0.8,
                label=f"{r['candidate']} ({r['large_stop_reason']})" if named else None,
                zorder=3 if r["_chosen"] else 2)
        ax.plot(r["large_stop_rotation_rad"], r["large_stop_torque_Nm"], END_MARKERS.get(r["large_stop_reason"], "*"),
                color=color, ms=9, mew=2)
        if np.isfinite(r["large_contact_rotation_rad"]):  # first contact (a schema-2 row's stop at contact: the same)
            ax.plot(r["large_contact_rotation_rad"], r["large_contact_torque_Nm"], "x", color=color, ms=9, mew=2)
        for kind, marker in (("cyclic", "o"), ("single", "s")):
            if np.isfinite(r[f"large_{kind}_limit_rotation_rad"]):
                ax.plot(r[f"large_{kind}_limit_rotation_rad"], r[f"large_{kind}_limit_torque_Nm"], marker, mfc="none",
                        color=color, ms=7)
    for torque, name in ((stall_Nm, "stall"), (impact_Nm, "impact")):
        ax.axhline(torque, color="k", ls="--", lw=0.8)
        ax.annotate(f"{name} {torque:.3g} Nm", (0, torque), fontsize=7, xytext=(2, 2), textcoords="offset points")
    ax.set(xlabel="hub rotation (rad)", ylabel="torque (Nm)")
    ax.set_title("Large-deflection torque curves\nx first contact; end: ^ limit point, v bifurcation, D unconverged; "
                 "strain limit passed: o cyclic, s single-event", fontsize=8)
    ax.grid(alpha=0.3)
    more = len(shown) - LEGEND_CURVES
    ax.legend(fontsize=6, loc="upper center", bbox_to_anchor=(0.5, -0.12),
              title=f"{more} more in thin lines, not named" if more > 0 else None, title_fontsize=6)
    return _save(fig, path)


def _save(fig, path: Path) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
