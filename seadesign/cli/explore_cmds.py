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
@click.option("--tolerance-mm", type=click.FloatRange(min=1e-4, max=1.0), default=0.01, show_default=True,
              help="STL chordal tolerance in mm.")
def explore(study: str, budget: int, batch: int | None, seed: int, jobs: int | None, quiet: bool, executor: str,
            scheduler: str | None, out_dir: Path, cache_dir: Path | None, tolerance_mm: float) -> None:
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
            _explore(study, budget, batch, seed, jobs, quiet, executor, scheduler, out_dir, cache_dir, tolerance_mm)
    except Interrupted as stop:
        click.echo(f"stopped by {stop.signal}; finished evaluations are saved; resume with: {resume}", err=True)
        click.get_current_context().exit(stop.exit_code)


def _explore(study: str, budget: int, batch: int | None, seed: int, jobs: int | None, quiet: bool, executor: str,
             scheduler: str | None, out_dir: Path, cache_dir: Path | None, tolerance_mm: float) -> None:
    from seadesign.design.study import load_study
    from seadesign.explore.loop import LoopSettings
    from seadesign.explore.study_run import explore_study
    from seadesign.report.exploration import headline, write_exploration
    from seadesign.report.explore_plots import column_label
    from seadesign.run.cache import DEFAULT_CACHE_DIR, Cache
    from seadesign.run.executors import default_jobs
    from seadesign.sweep.stages import SolverSettings

    logging.basicConfig(level=logging.WARNING, format="%(message)s")
    s = load_study(study)
    cache = Cache(cache_dir or DEFAULT_CACHE_DIR)
    solver = SolverSettings()
    folder = out_dir / s.name
    loop = LoopSettings(budget=budget, batch=batch or jobs or default_jobs(), seed=seed)
    run = explore_study(s, folder, loop, solver=solver, cache=cache, executor=executor, jobs=jobs, scheduler=scheduler,
                        quiet=quiet)
    written = write_exploration(s, run.problem, run.exploration, run.decision, run.sobol, folder, run.settings,
                                solver=solver, cache=cache, tolerance_mm=tolerance_mm)
    t, screened = run.exploration.evaluated, run.exploration.screened
    click.echo(f"{len(t)} full-path evaluations, {len(screened)} screenings "
               f"({int((~screened['valid'].astype(bool)).sum())} invalid), {run.wall_s:.1f} s; "
               f"stop: {run.exploration.stop_reason}")
    objective = run.problem.objectives[0]
    click.echo(headline(t, run.decision, column_label(objective), objective))
    click.echo(run.decision.predicted)
    for paths in written.values():
        for p in paths:
            if not quiet:
                click.echo(f"wrote {p}")
