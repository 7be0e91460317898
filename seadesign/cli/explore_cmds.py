"""`seadesign explore`: search a study's design space within a budget of full-path evaluations and report
the decision first."""

from __future__ import annotations

import logging
import shlex
import sys
from pathlib import Path

import click

from seadesign.cli import main


@main.command()
@click.argument("study")
@click.option("--budget", type=click.IntRange(min=2), default=80, show_default=True,
              help="Full-path evaluations (geometry, mesh, linear and large-deflection solve) at most (count); "
                   "screenings (geometry and validity only) are counted apart.")
@click.option("--batch", type=click.IntRange(min=1), default=None,
              help="Designs verified per round (count); default: --jobs.")
@click.option("--seed", type=int, default=0, show_default=True, help="Seed of the design of experiments and searches.")
@click.option("--jobs", type=click.IntRange(min=1), default=None, help="Worker processes (count); default: all cores.")
@click.option("--quiet", is_flag=True, help="No progress display (for scripts); the summary is still printed.")
@click.option("--executor", type=click.Choice(["local", "dask"]), default="local", show_default=True,
              help="local process pool, or a Dask distributed cluster.")
@click.option("--scheduler", default=None, metavar="HOST:PORT",
              help="Dask scheduler address (with --executor dask); a LocalCluster of --jobs workers when omitted.")
@click.option("--out", "out_dir", type=click.Path(file_okay=False, path_type=Path), default=Path("exports"),
              show_default=True, help="Output root (directory); files go to OUT/<study>/.")
@click.option("--cache-dir", type=click.Path(file_okay=False, path_type=Path), default=None,
              help="Stage cache directory; default $SEADESIGN_CACHE or ~/.cache/seadesign.")
@click.option("--calibration", type=click.Path(dir_okay=False, exists=True, path_type=Path), default=None,
              help="Calibration JSON from `seadesign explain --spring`: the material it names takes the fitted law; "
                   "outputs go to OUT/<study>-calibrated/.")
@click.option("--tolerance-mm", type=click.FloatRange(min=1e-4, max=1.0), default=0.01, show_default=True,
              help="STL chordal tolerance in mm.")
def explore(study: str, budget: int, batch: int | None, seed: int, jobs: int | None, quiet: bool, executor: str,
            scheduler: str | None, out_dir: Path, cache_dir: Path | None, calibration: Path | None,
            tolerance_mm: float) -> None:
    """Explore STUDY's design space (lists, ranges and continuous bounds under [design_space]): a design of
    experiments, surrogates of every output, constrained multi-objective search on them, and every proposed
    design verified on the full pipeline, until --budget is spent or the front stops moving. Writes
    results.parquet/csv (every evaluated design), front.csv, screened.csv, surrogate_loo.csv, sobol.csv, plots,
    report.html/md, and the chosen design's STL/STEP and spring.json to OUT/<study>/.

    Ctrl-C or SIGTERM stops it, keeping every finished evaluation; the same command resumes (the search is
    seeded, so it proposes the same designs and finds them stored).
    """
    from seadesign.run.interrupt import Interrupted, stop_on_signals

    resume = "seadesign " + shlex.join(sys.argv[1:])
    try:
        with stop_on_signals():
            _explore(study, budget, batch, seed, jobs, quiet, executor, scheduler, out_dir, cache_dir, calibration,
                     tolerance_mm)
    except Interrupted as stop:
        click.echo(f"stopped by {stop.signal}; finished evaluations are saved; resume with: {resume}", err=True)
        click.get_current_context().exit(stop.exit_code)


def _explore(study: str, budget: int, batch: int | None, seed: int, jobs: int | None, quiet: bool, executor: str,
             scheduler: str | None, out_dir: Path, cache_dir: Path | None, calibration: Path | None,
             tolerance_mm: float) -> None:
    """The explore command's work (`explore.pipeline`; see `explore`)."""
    from seadesign.explore.pipeline import run_exploration

    logging.basicConfig(level=logging.WARNING, format="%(message)s")
    result = run_exploration(study, budget, batch=batch, seed=seed, jobs=jobs, quiet=quiet, executor=executor,
                             scheduler=scheduler, out_dir=out_dir, cache_dir=cache_dir, tolerance_mm=tolerance_mm,
                             calibration=calibration)
    for line in result.lines(quiet):
        click.echo(line)
