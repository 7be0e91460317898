"""`seadesign sweep`: run every candidate of a study, rank, and write the report and spring.json."""

from __future__ import annotations

import json
import logging
import shlex
import sys
from pathlib import Path

import click

from seadesign.cli import main
from seadesign.errors import ConfigError
from seadesign.design.study import DEFAULT_STUDY, Study, load_study


CALIBRATION_KEYS = ("youngs_modulus_fitted_Pa", "youngs_modulus_Pa", "stiffness_scale")


def apply_calibration(study: Study, path: Path) -> tuple[Study, str]:
    """The study with its Young's modulus from a calibration JSON, first key found of:
    `youngs_modulus_fitted_Pa` (written by `explain`: the model material's E times the fitted
    stiffness scale) or `youngs_modulus_Pa` replace E (Pa); a bare `stiffness_scale` multiplies
    the study's E (right only when it was fitted against this study's material)."""
    try:
        data = json.loads(Path(path).read_text())
    except (OSError, json.JSONDecodeError) as exc:
        raise ConfigError(f"--calibration {path}: cannot be read as JSON ({exc})") from None
    key = next((k for k in CALIBRATION_KEYS if isinstance(data, dict) and k in data), None)
    if key is None:
        raise ConfigError(f"--calibration {path}: needs one of {', '.join(CALIBRATION_KEYS)} "
                          "(moduli in Pa, the scale a factor on E); `seadesign explain --spring` writes such a file")
    value = data[key]
    if not isinstance(value, (int, float)) or isinstance(value, bool) or not value > 0:
        raise ConfigError(f"--calibration {path}: '{key}' must be a positive number, got {value!r}")
    if len(study.materials) != 1:
        raise ConfigError(f"--calibration {path}: study '{study.name}' has the material as a design axis; a "
                          "calibration is fitted to one material: fix the material in the study to calibrate it")
    (name, material), = study.materials.items()
    scale = value if key == "stiffness_scale" else value / material.youngs_modulus_Pa
    note = f"calibrated from {Path(path).name} ({key} = {value:.4g}): E = {material.youngs_modulus_Pa * scale:.4g} Pa"
    return study.with_materials({name: material.scaled(scale, note)}), note


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
    """The sweep command's work (see `sweep`)."""
    from seadesign.run.cache import DEFAULT_CACHE_DIR, Cache
    from seadesign.sweep.rank import calibration_summary, handoff_verdict, rank
    from seadesign.report import write_outputs
    from seadesign.sweep.stages import SolverSettings
    from seadesign.sweep.runner import run_sweep, sweep_settings

    logging.basicConfig(level=logging.WARNING, format="%(message)s")
    s = load_study(study)
    baseline = None
    if calibration is not None:
        baseline = s
        s, note = apply_calibration(s, calibration)
        click.echo(note)
    cache = Cache(cache_dir or DEFAULT_CACHE_DIR)
    solver = SolverSettings()
    folder = out_dir / (f"{s.name}-calibrated" if baseline is not None else s.name)
    run = run_sweep(s, folder, settings=solver, cache=cache, executor=executor, jobs=jobs, scheduler=scheduler,
                    quiet=quiet)
    ranked, choice = rank(run.rows, s)
    settings = sweep_settings(s, solver)
    written = write_outputs(s, ranked, choice, folder, settings, solver=solver, cache=cache, export_all=export_all,
                            tolerance_mm=tolerance_mm)
    counts = ranked["status"].value_counts().to_dict()
    click.echo(f"{len(ranked)} candidates ({', '.join(f'{n} {k}' for k, n in counts.items())}); "
               f"{len(run.computed)} computed, {len(run.reused)} reused, {run.wall_s:.1f} s")
    click.echo(choice.explanation)
    if baseline is not None:
        base_run = run_sweep(baseline, out_dir / baseline.name, settings=solver, cache=cache,
                             executor=executor, jobs=jobs, scheduler=scheduler, quiet=quiet)
        base_ranked, base_choice = rank(base_run.rows, baseline)
        click.echo(calibration_summary(base_ranked, base_choice, ranked, choice, s))
    for kind, paths in written.items():
        for p in paths:
            if not quiet:
                click.echo(f"wrote {p}")
    if "spring" in written:
        click.echo(f"{written['spring'][0]}: {handoff_verdict(ranked, choice)}")
