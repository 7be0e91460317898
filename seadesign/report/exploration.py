"""Everything an exploration writes to exports/<study>/: the evaluated table, the front, the screened
designs, surrogate errors and Sobol indices, plots, the chosen design's STL/STEP, render and spring.json,
and the decision-first report."""

from __future__ import annotations

from dataclasses import asdict
from pathlib import Path

import pandas as pd

from seadesign.design.study import Study
from seadesign.explore.decision import Decision
from seadesign.explore.explorer import Exploration
from seadesign.report import write_renders, write_tables
from seadesign.report.document import Page, compact_table, fmt, write_html, write_markdown
from seadesign.report.explore_plots import column_label, fig_history, fig_loo, fig_parallel, fig_sobol
from seadesign.report.plots import fig_curves
from seadesign.report.sweep_page import objectives_text, study_text
from seadesign.run.atomic import atomic_write
from seadesign.sweep.requirements import window_verdict

FRONT_SHOWN = 12  # designs in the compact table


def loo_table(exploration: Exploration, outputs) -> pd.DataFrame:
    """Leave-one-out error of each output's surrogate over the solved designs."""
    rows = []
    for o, e in exploration.models.loo_errors(outputs).items():
        rows.append({"output": column_label(o), "designs": e.n, "mean |error| (%)": 100 * e.mean_abs_rel,
                     "largest |error| (%)": 100 * e.max_abs_rel})
    return pd.DataFrame(rows)


def headline(t: pd.DataFrame, d: Decision, objective_words: str, objective: str) -> str:
    if d.index is None:
        return "No design could be solved, so none can be chosen."
    r = t.loc[d.index]
    if d.feasible:
        return (f"Print {r['candidate']}: of the solved designs that meet every requirement, each judged, it has the "
                f"smallest {objective_words} ({fmt(r[objective])}).")
    if bool(r.get("conditional", False)):
        return (f"No solved design meets every requirement with each judged. The best conditional design, "
                f"{r['candidate']} ({objective_words} {fmt(r[objective])}), meets every requirement that can be "
                f"judged; the rest cannot be: {'; '.join(d.not_judged)}.")
    worst, margin = d.missed[0]
    return (f"No solved design meets every requirement. The nearest, {r['candidate']}, misses "
            f"'{worst}' by {-margin:.0%} (total miss {fmt(r['total_violation'])}).")


def why(t: pd.DataFrame, d: Decision, exploration: Exploration, counts: dict[str, int]) -> list[str]:
    points = []
    if d.index is not None:
        r = t.loc[d.index]
        points.append(f"{r['candidate']}: k at rest {fmt(r['k_Nm_per_rad'])} Nm/rad, mass {fmt(r['mass_g'])} g; its "
                      f"path ends at {fmt(r['large_stop_torque_Nm'])} Nm ({r['large_stop_reason']}); usable torque "
                      f"{fmt(r['usable_torque_Nm'])} Nm.")
        if d.missed:
            points.append("Missed there: " + "; ".join(f"{w} (by {-m:.0%})" for w, m in d.missed) + ".")
        points.append("Active there (met with less than 5 % to spare): "
                      + ("; ".join(f"{w} ({m:.1%} to spare)" for w, m in d.active) or "none") + ".")
        if d.not_judged:
            points.append("Not judged: " + "; ".join(d.not_judged) + ".")
    points.append(d.predicted)
    points.append(f"Verified on the full path: {counts['full']} designs; screened (geometry and validity only): "
                  f"{counts['screened']}, of which {counts['invalid']} invalid. Stop: {exploration.stop_reason}.")
    return points


def write_exploration(study: Study, problem, exploration: Exploration, decision: Decision, sobol: pd.DataFrame,
                      folder: Path, settings: dict, chosen_path=None) -> dict[str, list[Path]]:
    """Write the tables, figures, render (from the chosen design's path, `sweep.path_stage.PathResponse`) and
    report of an exploration; returns paths by kind (the table of every design under "tables")."""
    folder.mkdir(parents=True, exist_ok=True)
    xcols = [f"x{i}" for i in range(problem.encoding.dim)]  # the search's unit-cube coordinates: not written
    t = exploration.evaluated.drop(columns=xcols)
    t["pareto"] = t["front"]
    t["rank"] = pd.array([1 if i == decision.index else pd.NA for i in t.index], dtype="Int64")
    objective = problem.objectives[0]
    written = {"tables": write_tables(t, settings, folder)}
    front = t[t["front"]] if t["front"].any() else t.loc[[decision.index]] if decision.index is not None else t.iloc[[]]
    screened = exploration.screened.drop(columns=xcols)
    extra = {"front.csv": front, "screened.csv": screened, "surrogate_loo.csv": loo_table(exploration, problem.outputs),
             "sobol.csv": sobol}
    for name, frame in extra.items():
        path = folder / name
        atomic_write(path, lambda tmp, f=frame: f.to_csv(tmp, index=False))
        written["tables"].append(path)
    keys = [a.key for a in study.axes]
    figures = {
        "Torque curves of the evaluated designs (front in colour)": fig_curves(
            t, decision.index, study.load_cases.stall_torque_Nm, study.load_cases.impact_torque_Nm,
            folder / "torque_curves.png"),
        "Evaluated designs (green feasible, blue conditional, orange infeasible, grey invalid geometry; red the choice)": fig_parallel(
            t, screened[~screened["valid"].astype(bool)], keys, [*problem.objectives, "total_violation"],
            decision.index, folder / "parallel_coordinates.png"),
        "The search: best feasible design and least total violation against full evaluations": fig_history(
            exploration.rounds, objective, folder / "history.png"),
    }
    if len(sobol):  # outputs with a surrogate (at least surrogate.MIN_POINTS solved designs)
        figures["Sensitivity of each output to each axis (Sobol indices on the surrogates)"] = fig_sobol(
            sobol, folder / "sobol.png")
        figures["Surrogates: leave-one-out prediction of each solved design"] = fig_loo(
            exploration.models, list(problem.outputs), folder / "surrogate_loo.png")
    renders: dict[str, Path] = {}
    if decision.index is not None:
        row = t.loc[decision.index]
        renders = write_renders(row, chosen_path, folder)
    written["images"] = [*figures.values(), *renders.values()]
    counts = {"full": len(t), "screened": len(screened), "invalid": int((~screened["valid"].astype(bool)).sum())}
    shown = front.sort_values(objective).head(FRONT_SHOWN) if len(front) else front
    page = Page(
        title=f"Design exploration: {study.name}",
        headline=headline(t, decision, column_label(objective), objective), feasible=decision.feasible,
        why=[study.k_window.describe() + "." + ("" if decision.index is None else
                                                " " + window_verdict(t, decision.index, study)),
             *why(t, decision, exploration, counts)],
        table=compact_table(shown, [(k, k) for k in keys]),
        table_caption=("The verified front (every design solved on the full path)" if t["feasible"].any() else
                       "The conditional front (every judged requirement met, some not judged; every design solved on "
                       "the full path)" if t["front"].any() else
                       "The nearest solved design (no solved design meets every requirement)"),
        figures=figures, renders=renders,
        sections=[("Study", study_text(study)), ("Objectives", objectives_text(study)),
                  ("Surrogate leave-one-out error", "; ".join(
                      f"{r['output']}: {fmt(r['mean |error| (%)'])} % mean, {fmt(r['largest |error| (%)'])} % largest "
                      f"over {r['designs']} designs" for _, r in loo_table(exploration, problem.outputs).iterrows())),
                  ("Input files", study.files.describe())],
        details=[("Every evaluated design (full table)", compact_table(t.sort_values(objective), [(k, k) for k in keys])),
                 ("Rounds", pd.DataFrame([asdict(r) for r in exploration.rounds])),
                 ("Settings and versions", ", ".join(f"{k}: {v}" for k, v in settings.items()))],
    )
    written["report"] = [write_markdown(folder / "report.md", page), write_html(folder / "report.html", page)]
    return written
