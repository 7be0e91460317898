"""What a ranked sweep leaves in exports/<study>/: the chosen part's CAD files and spring.json from the stages
that own them, and the tables, figures, render and report that `report` writes from the results."""

from __future__ import annotations

import tempfile
from pathlib import Path

import pandas as pd

from seadesign.design.candidate import Candidate
from seadesign.design.study import Study
from seadesign.report import write_plots, write_renders, write_tables
from seadesign.report.document import write_html, write_markdown
from seadesign.report.sweep_page import Baseline, sweep_page
from seadesign.run.atomic import atomic_write
from seadesign.run.cache import Cache, digest
from seadesign.run.fingerprint import code_fingerprint
from seadesign.sweep.handoff import write_handoff
from seadesign.sweep.path_stage import PathResponse, path_key
from seadesign.sweep.rank import Choice
from seadesign.sweep.stages import SolverSettings, geometry_key

CAD_STAGE = "cad"  # the stage cache's folder of exported parts: {file name: bytes}


def cad_files(study: Study, candidate: Candidate, tolerance_mm: float, cache: Cache) -> dict[str, bytes]:
    """STL (chordal tolerance `tolerance_mm`, mm) and STEP of a candidate's part by file name; from the stage
    cache while the geometry, the tolerance and the exporter's code are unchanged."""
    key = digest(geometry_key(study, candidate), tolerance_mm, code_fingerprint("seadesign.design.export"))
    files = cache.get(CAD_STAGE, key)
    if files is None:
        from seadesign.design.export import export_candidate  # CadQuery: only when a part is exported afresh

        with tempfile.TemporaryDirectory(prefix="seadesign-cad-") as folder:
            files = {p.name: p.read_bytes()
                     for p in export_candidate(candidate, study.check(candidate)[1], folder, tolerance_mm)}
        cache.put(CAD_STAGE, key, files)
    return files


def export_cad(study: Study, rows: pd.DataFrame, folder: Path, tolerance_mm: float, cache: Cache) -> list[Path]:
    """STL + STEP of the given rows' candidates in `folder`."""
    return [atomic_write(folder / name, lambda tmp, data=data: tmp.write_bytes(data))
            for _, row in rows.iterrows()
            for name, data in cad_files(study, study.candidate_of_row(row), tolerance_mm, cache).items()]


def chosen_path(study: Study, row: pd.Series, solver: SolverSettings, cache: Cache) -> PathResponse | None:
    """The stored large-deflection path of a row's candidate (None when it is not in the cache)."""
    return cache.get("path", path_key(study, study.candidate_of_row(row), solver))


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
        renders = write_renders(row, chosen_path(study, row, solver, cache), folder)
        if not export_all:
            cad_rows = t.loc[[choice.index]]
        selection = {"meets_requirements": choice.feasible, "conditional": choice.conditional,
                     "failed_constraints": str(row["failed_constraints"]), "not_judged": str(row["not_judged"]),
                     "deciding_objective": study.requirements.objectives[0], "rank": int(row["rank"]),
                     "explanation": choice.explanation}
        written["spring"] = [write_handoff(study, t, row, folder, settings, selection)]
    written["cad"] = export_cad(study, cad_rows, folder, tolerance_mm, cache)
    written["images"] = [*figures.values(), *renders.values()]
    page = sweep_page(study, t, choice, settings, figures, renders, baseline)
    written["report"] = [write_markdown(folder / "report.md", page), write_html(folder / "report.html", page)]
    return written
