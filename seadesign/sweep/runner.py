"""Run every candidate of a study and collect one result row per candidate.

Rows are written as they arrive, one JSON file per candidate under `<out>/rows/`, named by a
hash of every input of that candidate (atomic write: temp file + rename). A rerun reuses rows
whose inputs are unchanged (failed ones are retried), so an interrupted sweep resumes where it
stopped; stages of the others come from the content-addressed cache when their own inputs are
unchanged. Interrupted (Ctrl-C, SIGTERM), the sweep stops its workers at once, removes their
half-written files and raises `SweepStopped` with the count of saved rows.
Invalid candidates keep their reasons; a candidate whose mesher or solver fails keeps the
error and the sweep goes on.
"""

from __future__ import annotations

import json
import os
import time
import traceback
from dataclasses import dataclass, field
from pathlib import Path

import pandas as pd

from seadesign.design.candidate import Candidate
from seadesign.design.study import Study
from seadesign.run.fingerprint import code_fingerprint
from seadesign.run.atomic import atomic_write
from seadesign.run.cache import Cache, digest, package_versions
from seadesign.run.executors import default_jobs, execute
from seadesign.run.heavy_stage import heavy_stage_busy
from seadesign.run.interrupt import Interrupted, remove_partial_files
from seadesign.run.progress import ProgressDisplay
from seadesign.sweep.path_stage import path_key, path_response
from seadesign.sweep.stages import (SolverSettings, check_geometry, coarse_k, fea_key, fea_response, geometry_key,
                                    part_source)
from seadesign.sweep.table import candidate_columns, fea_columns, geometry_columns, path_columns


@dataclass(frozen=True)
class Job:
    """One candidate to evaluate (picklable: it travels to worker processes)."""

    index: int
    study: Study
    candidate: Candidate
    settings: SolverSettings
    cache: Cache
    row_key: str
    screen: bool = False  # only the geometry stage (validity, volume, mass): the explorer's cheap screening


class SweepStopped(Interrupted):
    """A sweep stopped by a signal: how many candidates have saved rows, and where."""

    def __init__(self, signal_name: str, saved: int, total: int, rows_dir: Path) -> None:
        super().__init__(signal_name)
        self.saved, self.total, self.rows_dir = saved, total, rows_dir


@dataclass
class SweepRun:
    """The rows of a sweep and how they were obtained."""

    rows: pd.DataFrame
    computed: list[int] = field(default_factory=list)  # candidate indices evaluated in this run
    reused: list[int] = field(default_factory=list)  # indices whose stored row was reused
    wall_s: float = 0.0


def row_key(study: Study, candidate: Candidate, settings: SolverSettings) -> str:
    """Hash of every input of one candidate's row (its axis values, geometry, mesh, material, loads,
    solver, large-deflection path, versions) and of the code that turns the stage outputs into the row
    (this module and the table's columns)."""
    return digest("row", candidate.values, fea_key(study, candidate, settings), path_key(study, candidate, settings),
                  settings.k_error_estimate, geometry_key(study, candidate),
                  study.load_cases, study.bearing_radius_mm, candidate.material, code_fingerprint(__name__))


def screen_key(study: Study, candidate: Candidate) -> str:
    """Hash of every input of one candidate's screening row (its axis values, geometry verdict, material)."""
    return digest("screen", candidate.values, geometry_key(study, candidate), candidate.material,
                  code_fingerprint(__name__))


def evaluate(job: Job, sink) -> dict:
    """One candidate's row (only its geometry when screening). Never raises for a candidate's own failure:
    the error is the row."""
    row = candidate_columns(job.candidate, job.row_key)
    t0 = time.perf_counter()

    def stage(name: str) -> None:
        sink.put((job.index, name))

    try:
        stage("geometry")
        checked, part = check_geometry(job.study, job.candidate, job.cache)
        row.update(geometry_columns(checked))
        if not checked.valid:
            row.update(status="invalid", reason="; ".join(checked.reasons))
        elif not job.screen:
            part_of = part_source(job.study, checked, part, stage)

            def path():
                return path_response(job.study, checked, part_of, job.settings, job.cache, stage)

            early = path() if heavy_stage_busy() else None  # another worker factors: the path first, not a wait
            unit = fea_response(job.study, checked, part_of, job.settings, job.cache, stage)
            coarse = (coarse_k(job.study, checked, part_of, job.settings, job.cache, stage)
                      if job.settings.k_error_estimate else None)
            row.update(fea_columns(unit, coarse, job.study))
            row.update(path_columns(path() if early is None else early, job.study))
    except Exception as exc:  # noqa: BLE001 - a failing candidate is a result, not a crash
        row.update(status="failed", reason=f"{type(exc).__name__}: {exc}".strip(),
                   traceback=traceback.format_exc(limit=4))
    row["elapsed_s"] = time.perf_counter() - t0
    return row


def write_row(folder: Path, row: dict) -> Path:
    """Atomically write one row as JSON (key order kept: the same columns cold and warm)."""
    return atomic_write(folder / f"{row['row_key']}.json", lambda tmp: tmp.write_text(json.dumps(row)))


def read_row(folder: Path, key: str) -> dict | None:
    try:
        return json.loads((folder / f"{key}.json").read_text())
    except (FileNotFoundError, json.JSONDecodeError):
        return None


def write_table_atomic(df: pd.DataFrame, path: Path) -> None:
    """A table as CSV, atomically."""
    atomic_write(path, lambda tmp: df.to_csv(tmp, index=False))


def run_sweep(study: Study, out_dir: Path, **options) -> SweepRun:
    """Evaluate every candidate of the study's grid (see `run_candidates`) and return the rows in study order."""
    return run_candidates(study, study.candidates(), out_dir, **options)


def run_candidates(study: Study, candidates: list[Candidate], out_dir: Path, *, screen: bool = False,
                   settings: SolverSettings = SolverSettings(), cache: Cache | None = None, executor: str = "local",
                   jobs: int | None = None, scheduler: str | None = None, quiet: bool = False, on_row=None,
                   display: ProgressDisplay | None = None) -> SweepRun:
    """Evaluate `candidates` (reusing stored rows with unchanged inputs; rows in `<out>/rows/`, screening rows,
    geometry only, in `<out>/screen/`) and return the rows in the given order. `on_row(row)` is called as each
    computed row is stored (progress hooks, tests); `display` is a progress display the caller keeps across
    calls (one per call by default)."""
    t0 = time.perf_counter()
    cache = cache or Cache()
    rows_dir = Path(out_dir) / ("screen" if screen else "rows")
    keys = [screen_key(study, c) if screen else row_key(study, c, settings) for c in candidates]
    rows: dict[int, dict] = {}
    for i, key in enumerate(keys):
        stored = read_row(rows_dir, key)
        if stored is not None and stored["status"] != "failed":  # failures are retried
            rows[i] = stored
    reused = sorted(rows)
    todo = [Job(i, study, candidates[i], settings, cache, keys[i], screen) for i in range(len(candidates))
            if i not in rows]
    labels = {j.index: j.candidate.name for j in todo}
    if display is None:
        display = ProgressDisplay(len(candidates), len(reused), labels, quiet)
    else:
        display.labels = labels
        display.add_reused(len(reused))
    partial_csv = Path(out_dir) / ("screen.partial.csv" if screen else "results.partial.csv")
    killed: list[int] = []
    stream = execute(evaluate, todo, executor, jobs or default_jobs(), scheduler, display.stage, display.tick, killed)
    try:
        for job, row in stream:
            write_row(rows_dir, row)
            rows[job.index] = row
            display.finished(job.index, row["status"])
            write_table_atomic(pd.DataFrame([rows[i] for i in sorted(rows)]), partial_csv)
            if on_row is not None:
                on_row(row)
    except KeyboardInterrupt as exc:
        stream.close()  # cancels what is pending and kills the workers
        remove_partial_files([rows_dir, Path(cache.root)], killed + [os.getpid()])
        display.close()
        raise SweepStopped(getattr(exc, "signal", "SIGINT"), len(rows), len(candidates), rows_dir) from None
    finally:
        stream.close()
    display.close()
    partial_csv.unlink(missing_ok=True)
    table = pd.DataFrame([rows[i] for i in range(len(candidates))])
    return SweepRun(table, [j.index for j in todo], reused, time.perf_counter() - t0)


def sweep_settings(study: Study, settings: SolverSettings) -> dict:
    """Settings and versions recorded next to the results."""
    from dataclasses import asdict

    return {"study": study.name, "files": asdict(study.files),
            "materials": {k: asdict(m) for k, m in study.materials.items()}, "mesh": asdict(study.mesh),
            "solver": asdict(settings), "ranking": asdict(study.ranking), "versions": package_versions()}
