"""The results' files in exports/<study>/: tables, plots, renders and the report pages (`report.document`);
they receive results and write, computing nothing (the CAD files and spring.json come from `sweep.outputs`)."""

from __future__ import annotations

import json
from pathlib import Path

import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq

from seadesign.run.atomic import atomic_write
from seadesign.sweep.rank import Choice
from seadesign.design.space import axis_label
from seadesign.design.study import Study



def write_tables(t: pd.DataFrame, settings: dict, folder: Path) -> list[Path]:
    """results.parquet (settings and versions in its metadata), results.csv and settings.json."""
    folder.mkdir(parents=True, exist_ok=True)
    table = pa.Table.from_pandas(t.drop(columns=["traceback"], errors="ignore"), preserve_index=False)
    table = table.replace_schema_metadata({**(table.schema.metadata or {}),
                                           b"seadesign.settings": json.dumps(settings, default=str).encode()})
    paths = [folder / "results.parquet", folder / "results.csv", folder / "settings.json"]
    atomic_write(paths[0], lambda tmp: pq.write_table(table, tmp))
    atomic_write(paths[1], lambda tmp: t.drop(columns=["traceback"], errors="ignore").to_csv(tmp, index=False))
    atomic_write(paths[2], lambda tmp: tmp.write_text(json.dumps(settings, indent=2, sort_keys=True, default=str) + "\n"))
    return paths


def write_plots(study: Study, t: pd.DataFrame, choice: Choice, folder: Path) -> dict[str, Path]:
    """The sweep's figures by caption, over the study's design axes; unchanged results keep their PNGs."""
    from seadesign.report.plots import fig_curves, fig_k, fig_pareto, fig_reaction_displacement

    axes = [a.key for a in study.axes]
    thesis = axes[:2] == ["beam_count", "beam_thickness_mm"]
    figures = {
        f"Reaction force and displacement vs {axis_label(axes[0])}" + (" (thesis fig. 5.3 analogue)" if thesis else ""):
            (lambda table, path: fig_reaction_displacement(table, axes, path), folder / "reaction_displacement.png"),
        f"k vs {axis_label(axes[0])}": (lambda table, path: fig_k(table, axes, path), folder / f"k_vs_{axes[0]}.png"),
        "Pareto front": (lambda table, path: fig_pareto(table, choice.index, path), folder / "pareto.png"),
        "Large-deflection torque curves": (
            lambda table, path: fig_curves(table, choice.index, study.load_cases.stall_torque_Nm,
                                           study.load_cases.impact_torque_Nm, path), folder / "torque_curves.png"),
    }
    for draw, path in figures.values():
        draw(t, path)
    return {caption: path for caption, (_, path) in figures.items()}


def write_renders(row: pd.Series, response, folder: Path) -> dict[str, Path]:
    """The chosen row's large-deflection state at the stall torque (or where its path stops) from its path
    `response` (`sweep.path_stage.PathResponse`), by caption; none without a response or off-screen rendering."""
    from seadesign.report.renders import render_path

    reached = bool(row["large_stall_reached"])
    where = "at the stall torque" if reached else f"where its path stops ({row['large_stop_reason']})"
    title = f"{row['candidate']}: large deflection {where}"
    if response is None or render_path(response, float(row["large_stall_strain_limit"]), title,
                                       folder / "chosen_large_deflection.png") is None:
        return {}
    return {f"Chosen part {where}, true scale (colour: largest tensile principal strain, %)":
            folder / "chosen_large_deflection.png"}
