"""`seadesign sweep`: run every candidate of a study, rank, and write the report and spring.json."""

from __future__ import annotations

import logging
import shlex
import sys
from pathlib import Path

import click

from seadesign.cli import main
from seadesign.design.study import DEFAULT_STUDY


@main.command()
@click.argument("study", default=str(DEFAULT_STUDY.stem), required=False)
@click.option("--jobs", type=click.IntRange(min=1), default=None,
              help="Worker processes (count); default: all cores.")
@click.option("--quiet", is_flag=True, help="No progress display (for scripts); the summary is still printed.")
@click.option("--executor", type=click.Choice(["local", "dask"]), default="local", show_default=True,
              help="local process pool, or a Dask distributed cluster.")
@click.option("--scheduler", default=None, metavar="HOST:PORT",
              help="Dask scheduler address (with --executor dask); a LocalCluster of --jobs workers when omitted.")
@click.option("--export-all", is_flag=True, help="STL + STEP (mm) of every valid candidate, not only the chosen one.")
@click.option("--out", "out_dir", type=click.Path(file_okay=False, path_type=Path), default=Path("exports"),
              show_default=True, help="Output root (directory); files go to OUT/<study>/.")
@click.option("--calibration", type=click.Path(dir_okay=False, exists=True, path_type=Path), default=None,
              help="Calibration JSON (from `seadesign explain --spring`) whose fitted modulus replaces the material's "
                   "Young's modulus; outputs go to OUT/<study>-calibrated/ and the choice with and without it, "
                   "and whether each carries the standing load, is printed.")
@click.option("--cache-dir", type=click.Path(file_okay=False, path_type=Path), default=None,
              help="Stage cache directory; default $SEADESIGN_CACHE or ~/.cache/seadesign.")
@click.option("--tolerance-mm", type=click.FloatRange(min=1e-4, max=1.0), default=0.01, show_default=True,
              help="STL chordal tolerance in mm.")
def sweep(study: str, jobs: int | None, quiet: bool, executor: str, scheduler: str | None, export_all: bool,
          out_dir: Path, calibration: Path | None, cache_dir: Path | None, tolerance_mm: float) -> None:
    """Run every candidate of STUDY (geometry, validity, mesh, both linear load cases, the large-deflection
    torque path), rank them on the paths and write results.parquet/csv, plots, report.html/md, STL/STEP and spring.json to OUT/<study>/.

    Ctrl-C or SIGTERM stops it within a second or two, keeping every finished candidate; the same
    command resumes, and unchanged stages come from the cache. Units: lengths mm where named,
    otherwise SI (N, Nm, rad, Pa).
    """
    from seadesign.run.interrupt import Interrupted, stop_on_signals
    from seadesign.sweep.runner import SweepStopped

    resume = "seadesign " + shlex.join(sys.argv[1:])
    try:
        with stop_on_signals():
            _sweep(study, jobs, quiet, executor, scheduler, export_all, out_dir, calibration, cache_dir, tolerance_mm)
    except SweepStopped as stop:
        click.echo(f"stopped by {stop.signal}: {stop.saved} of {stop.total} candidates finished and saved in "
                   f"{stop.rows_dir} (no half-written file left); resume with: {resume}", err=True)
        click.get_current_context().exit(stop.exit_code)
    except Interrupted as stop:
        click.echo(f"stopped by {stop.signal}; finished candidates are saved; resume with: {resume}", err=True)
        click.get_current_context().exit(stop.exit_code)


def _sweep(study: str, jobs: int | None, quiet: bool, executor: str, scheduler: str | None, export_all: bool,
           out_dir: Path, calibration: Path | None, cache_dir: Path | None, tolerance_mm: float) -> None:
    """The sweep command's work (`sweep.pipeline`; see `sweep`)."""
    from seadesign.design.study import load_study
    from seadesign.sweep.pipeline import apply_calibration, sweep_and_write

    logging.basicConfig(level=logging.WARNING, format="%(message)s")
    s = load_study(study)
    baseline = note = None
    if calibration is not None:
        baseline = s
        s, note = apply_calibration(s, calibration)
        click.echo(note)
    result = sweep_and_write(s, out_dir, baseline=baseline, jobs=jobs, quiet=quiet, executor=executor,
                             scheduler=scheduler, export_all=export_all, cache_dir=cache_dir, tolerance_mm=tolerance_mm,
                             calibration_note=note)
    for line in result.lines(quiet):
        click.echo(line)
