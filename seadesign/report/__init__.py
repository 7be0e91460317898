"""Everything a sweep writes to exports/<study>/: tables, plots, renders, report, CAD files, spring.json."""

from __future__ import annotations

import json
import logging
from pathlib import Path

import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq

from seadesign.cache import Cache, digest
from seadesign.handoff import write_spring
from seadesign.rank import Choice
from seadesign.report.document import write_html, write_markdown
from seadesign.report.handoff import spring_document
from seadesign.report.plots import fig_k, fig_pareto, fig_reaction_displacement
from seadesign.report.renders import render_case
from seadesign.stages import SolverSettings, fea_key, geometry_key
from seadesign.study import Study

log = logging.getLogger(__name__)


def write_tables(t: pd.DataFrame, settings: dict, folder: Path) -> list[Path]:
    """results.parquet (settings and versions in its metadata), results.csv and settings.json."""
    folder.mkdir(parents=True, exist_ok=True)
    table = pa.Table.from_pandas(t.drop(columns=["traceback"], errors="ignore"), preserve_index=False)
    table = table.replace_schema_metadata({**(table.schema.metadata or {}),
                                           b"seadesign.settings": json.dumps(settings, default=str).encode()})
    paths = [folder / "results.parquet", folder / "results.csv", folder / "settings.json"]
    tmp = paths[0].with_suffix(".tmp.parquet")
    pq.write_table(table, tmp)
    tmp.replace(paths[0])
    t.drop(columns=["traceback"], errors="ignore").to_csv(paths[1].with_suffix(".tmp.csv"), index=False)
    paths[1].with_suffix(".tmp.csv").replace(paths[1])
    paths[2].write_text(json.dumps(settings, indent=2, sort_keys=True, default=str) + "\n")
    return paths


def export_cad(study: Study, rows: pd.DataFrame, folder: Path, tolerance_mm: float) -> list[Path]:
    """STL + STEP of the given candidates; files whose geometry key is unchanged are kept."""
    from seadesign.candidates import check_candidate
    from seadesign.export import export_candidate

    out = []
    for _, r in rows.iterrows():
        params = study.params(int(r["beam_count"]), float(r["beam_thickness_mm"]))
        stem = f"{params.beam_count}beams_{params.beam_thickness_mm:g}mm"
        files = [folder / f"{stem}.stl", folder / f"{stem}.step"]
        stamp = folder / f".{stem}.key"
        key = digest(geometry_key(study, params), tolerance_mm)
        if all(f.exists() for f in files) and stamp.exists() and stamp.read_text() == key:
            out += files
            continue
        out += export_candidate(check_candidate(study, params), folder, tolerance_mm)
        stamp.write_text(key)
    return out


def write_outputs(study: Study, t: pd.DataFrame, choice: Choice, folder: Path, settings: dict, *,
                  solver: SolverSettings, cache: Cache, export_all: bool = False,
                  tolerance_mm: float = 0.01) -> dict[str, list[Path]]:
    """Write every output of a ranked sweep; returns paths by kind."""
    folder.mkdir(parents=True, exist_ok=True)
    written: dict[str, list[Path]] = {"tables": write_tables(t, settings, folder)}
    images = {
        "Reaction force and displacement vs beam count (thesis fig. 5.3 analogue)":
            fig_reaction_displacement(t, folder / "reaction_displacement.png"),
        "k vs beam count": fig_k(t, folder / "k_vs_beams.png"),
        "Pareto front": fig_pareto(t, choice.index, folder / "pareto.png"),
    }
    cad_rows = t[t["status"] != "invalid"] if export_all else t.iloc[[]]
    if choice.index is not None:
        row = t.loc[choice.index]
        params = study.params(int(row["beam_count"]), float(row["beam_thickness_mm"]))
        unit = cache.get("fea", fea_key(study, params, solver))
        for case in ("stall", "impact"):
            torque = float(row[f"{case}_torque_Nm"])
            path = render_case(unit, case, torque, f"{row['candidate']}: {case}, {torque:.3g} Nm",
                               folder / f"chosen_{case}.png") if unit is not None else None
            if path is not None:
                images[f"Chosen part under the {case} load case (colour: von Mises, MPa)"] = path
        if not export_all:
            cad_rows = t.loc[[choice.index]]
        selection = {"feasible": choice.feasible, "failed_constraints": str(row["failed_constraints"]),
                     "score": float(row["score"]), "rank": int(row["rank"]), "explanation": choice.explanation}
        inputs_hash = digest("spring", list(t["row_key"]), study.ranking, study.robot, study.actuator)
        written["spring"] = [write_spring(spring_document(study, row, inputs_hash, settings["versions"], selection),
                                          folder / "spring.json")]
    written["cad"] = export_cad(study, cad_rows, folder, tolerance_mm)
    written["images"] = list(images.values())
    written["report"] = [write_markdown(folder / "report.md", study, t, choice.explanation, settings, images),
                         write_html(folder / "report.html", study, t, choice.explanation, settings, images)]
    return written
