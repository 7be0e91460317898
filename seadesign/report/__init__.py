"""Everything a sweep writes to exports/<study>/: tables, plots, renders, report, CAD files, spring.json."""

from __future__ import annotations

import json
import logging
from pathlib import Path

import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq

from seadesign.run.atomic import atomic_write
from seadesign.run.cache import Cache, digest
from seadesign.run.fingerprint import code_fingerprint
from seadesign.design.spring import write_spring
from seadesign.sweep.rank import Choice
from seadesign.report.document import write_html, write_markdown
from seadesign.report.sweep_page import Baseline, sweep_page
from seadesign.sweep.handoff import spring_document
from seadesign.sweep.path_stage import path_key
from seadesign.sweep.stages import SolverSettings, geometry_key
from seadesign.design.space import axis_label
from seadesign.design.study import Study

log = logging.getLogger(__name__)


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


def up_to_date(files: list[Path], key: str) -> bool:
    """True when every file exists and was written from inputs hashing to `key` (see `stamp`)."""
    return all(f.exists() and _stamp_path(f).exists() and _stamp_path(f).read_text() == key for f in files)


def stamp(files: list[Path], key: str) -> None:
    """Record that `files` were written from inputs hashing to `key` (hidden .<name>.key beside each)."""
    for f in files:
        _stamp_path(f).write_text(key)


def _stamp_path(file: Path) -> Path:
    return file.with_name(f".{file.name}.key")


def export_cad(study: Study, rows: pd.DataFrame, folder: Path, tolerance_mm: float) -> list[Path]:
    """STL + STEP of the given candidates; files whose geometry key is unchanged are kept."""
    out = []
    for _, r in rows.iterrows():
        candidate = study.candidate_of_row(r)
        files = [folder / f"{candidate.stem}.stl", folder / f"{candidate.stem}.step"]
        key = digest(geometry_key(study, candidate), tolerance_mm, code_fingerprint("seadesign.design.export"))
        if not up_to_date(files, key):
            from seadesign.design.export import export_candidate  # CadQuery: only when a file is (re)written

            export_candidate(candidate, study.check(candidate)[1], folder, tolerance_mm)
            stamp(files, key)
        out += files
    return out


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
    numbers = t.drop(columns=["elapsed_s", "traceback"], errors="ignore")
    key = digest("plots", numbers[sorted(numbers.columns)].to_json(), choice.index, axes,
                 code_fingerprint("seadesign.report.plots"))
    paths = [path for _, path in figures.values()]
    if not up_to_date(paths, key):
        for draw, path in figures.values():
            draw(t, path)
        stamp(paths, key)
    return {caption: path for caption, (_, path) in figures.items()}


def write_renders(study: Study, row: pd.Series, folder: Path, solver: SolverSettings,
                  cache: Cache) -> dict[str, Path]:
    """The chosen candidate's large-deflection state at the stall torque (or where its path stops), by caption
    (none when its path is not cached or off-screen rendering is unavailable); unchanged inputs keep the PNG."""
    from seadesign.report.renders import render_path

    key_path = path_key(study, study.candidate_of_row(row), solver)
    reached = bool(row["large_stall_reached"])
    where = "at the stall torque" if reached else f"where its path stops ({row['large_stop_reason']})"
    title = f"{row['candidate']}: large deflection {where}"
    path = folder / "chosen_large_deflection.png"
    key = digest("render", key_path, title, code_fingerprint("seadesign.report.renders"))
    if not up_to_date([path], key):
        response = cache.get("path", key_path)
        if response is None or render_path(response, float(row["large_stall_strain_limit"]), title, path) is None:
            return {}
        stamp([path], key)
    return {f"Chosen part {where}, true scale (colour: largest tensile principal strain, %)": path}


def write_outputs(study: Study, t: pd.DataFrame, choice: Choice, folder: Path, settings: dict, *,
                  solver: SolverSettings, cache: Cache, export_all: bool = False,
                  tolerance_mm: float = 0.01, baseline: Baseline | None = None) -> dict[str, list[Path]]:
    """Write every output of a ranked sweep (a calibrated one compared with its `baseline`); returns paths by kind."""
    folder.mkdir(parents=True, exist_ok=True)
    written: dict[str, list[Path]] = {"tables": write_tables(t, settings, folder)}
    figures = write_plots(study, t, choice, folder)
    renders: dict[str, Path] = {}
    cad_rows = t[t["status"] != "invalid"] if export_all else t.iloc[[]]
    if choice.index is not None:
        row = t.loc[choice.index]
        renders = write_renders(study, row, folder, solver, cache)
        if not export_all:
            cad_rows = t.loc[[choice.index]]
        selection = {"meets_requirements": choice.feasible, "conditional": choice.conditional,
                     "failed_constraints": str(row["failed_constraints"]), "not_judged": str(row["not_judged"]),
                     "deciding_objective": study.requirements.objectives[0], "rank": int(row["rank"]),
                     "explanation": choice.explanation}
        written["spring"] = [write_handoff(study, t, row, folder, settings, selection)]
    written["cad"] = export_cad(study, cad_rows, folder, tolerance_mm)
    written["images"] = [*figures.values(), *renders.values()]
    page = sweep_page(study, t, choice, settings, figures, renders, baseline)
    written["report"] = [write_markdown(folder / "report.md", page), write_html(folder / "report.html", page)]
    return written


def write_handoff(study: Study, t: pd.DataFrame, row: pd.Series, folder: Path, settings: dict,
                  selection: dict) -> Path:
    """spring.json of the chosen row, hashed over every evaluated row and the study's robot data."""
    inputs_hash = digest("spring", list(t["row_key"]), study.ranking, study.requirements, study.robot, study.actuator)
    return write_spring(spring_document(study, row, inputs_hash, settings["versions"], selection), folder / "spring.json")
