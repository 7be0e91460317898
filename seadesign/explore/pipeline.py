"""An exploration end to end, as `seadesign explore` runs it: the study explored within a budget of full-path
evaluations (`explore.study_run`), every output written (`report.exploration`), and the decision in words.

Outputs go to ``OUT/<study>/``. Lengths in mm where named, otherwise SI (N, Nm, rad, Pa).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from seadesign.design.study import Study, load_study
from seadesign.explore.study_run import StudyExploration

if TYPE_CHECKING:
    import pandas as pd
    from matplotlib.axes import Axes


@dataclass
class ExplorationResult:
    """A finished exploration: what was verified, the decision, the files written.

    Attributes
    ----------
    study : Study
        The study explored.
    run : StudyExploration
        The problem, the exploration (``run.exploration.evaluated``: one row per full evaluation), the
        decision (``run.decision.index`` into it, None when nothing was solved), the Sobol indices.
    folder : Path
        Where the outputs are.
    written : dict of str to list of Path
        The files written, by kind (tables, images, spring, cad).
    calibration : str
        With a calibration: which material was calibrated, and how (empty without).
    """

    study: Study
    run: StudyExploration
    folder: Path
    written: dict[str, list[Path]]
    calibration: str = ""

    def lines(self, quiet: bool = False) -> list[str]:
        """What `seadesign explore` prints when it is done.

        Parameters
        ----------
        quiet : bool
            Leave out the list of files written.

        Returns
        -------
        list of str
            The counts, time and stop reason; the decision; the surrogates' evidence; the files written.

        Examples
        --------
        >>> print("\\n".join(result.lines(quiet=True)))
        """
        from seadesign.report.exploration import headline
        from seadesign.report.explore_plots import column_label

        t, screened = self.run.exploration.evaluated, self.run.exploration.screened
        objective = self.run.problem.objectives[0]
        out = [f"{len(t)} full-path evaluations, {len(screened)} screenings "
               f"({int((~screened['valid'].astype(bool)).sum())} invalid), {self.run.wall_s:.1f} s; "
               f"stop: {self.run.exploration.stop_reason}",
               headline(t, self.run.decision, column_label(objective), objective),
               self.run.decision.predicted]
        if self.calibration:
            out.insert(0, self.calibration)
        if not quiet:
            out += [f"wrote {p}" for paths in self.written.values() for p in paths]
        return out

    def to_frame(self) -> pd.DataFrame:
        """Every fully evaluated design (a copy), without the search's unit-cube coordinates.

        Returns
        -------
        pandas.DataFrame
            One row per design: its axis values, the results columns with units in the names (``k_Nm_per_rad``,
            ``mass_g``, ``large_stop_torque_Nm``, ...), ``total_violation``, ``feasible``, ``front``, ``round``
            and ``chosen``.

        Examples
        --------
        >>> result.to_frame().query("front")[["candidate", "mass_g"]]
        """
        t = self.run.exploration.evaluated
        t = t.drop(columns=[c for c in t.columns if c.startswith("x") and c[1:].isdigit()])
        return t.assign(chosen=t.index == self.run.decision.index)

    def plot(self, ax: Axes | None = None) -> Axes:
        """The deciding objective against total requirement violation (-) of every evaluated design: the
        front in colour, the choice circled.

        Parameters
        ----------
        ax : matplotlib.axes.Axes, optional
            Where to draw; None: a new figure.

        Returns
        -------
        matplotlib.axes.Axes
            The axes drawn on.

        Examples
        --------
        >>> result.plot().figure.savefig("designs.png")
        """
        import matplotlib.pyplot as plt

        from seadesign.report.explore_plots import column_label

        if ax is None:
            _, ax = plt.subplots(figsize=(6, 4.5))
        t = self.to_frame()
        objective = self.run.problem.objectives[0]
        front = t["front"].astype(bool)
        ax.plot(t.loc[~front, objective], t.loc[~front, "total_violation"], "o", color="0.6", ms=4, label="evaluated")
        ax.plot(t.loc[front, objective], t.loc[front, "total_violation"], "o", color="C0", ms=5, label="front")
        chosen = t[t["chosen"]]
        ax.plot(chosen[objective], chosen["total_violation"], "o", mfc="none", mec="r", ms=11, mew=2, label="chosen")
        ax.set(xlabel=column_label(objective), ylabel="total violation (-)",
               title=f"Designs evaluated in {self.study.name}")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
        return ax


def run_exploration(study: str | Path | Study, budget: int = 80, *, batch: int | None = None, seed: int = 0,
                    jobs: int | None = None, quiet: bool = False, executor: str = "local",
                    scheduler: str | None = None, out_dir: str | Path = Path("exports"),
                    cache_dir: str | Path | None = None, tolerance_mm: float = 0.01,
                    calibration: str | Path | None = None) -> ExplorationResult:
    """Explore a study's design space (lists, ranges and continuous bounds under ``[design_space]``) and write
    the results, as `seadesign explore`: a design of experiments, surrogates of every output, constrained
    multi-objective search on them, every proposal verified on the full pipeline, until the budget is spent or
    the front stops moving. Resumable: the search is seeded and finds its stored evaluations.

    Parameters
    ----------
    study : str, Path or Study
        A study name (``NAME.toml`` here, else the packaged one), a path, or a loaded study.
    budget : int
        Full-path evaluations at most (count, at least 2); screenings are counted apart.
    batch : int, optional
        Designs verified per round (count); None: `jobs`, else all cores.
    seed : int
        Seed of the design of experiments and the searches.
    jobs : int, optional
        Worker processes (count); None: all cores.
    quiet : bool
        No progress display.
    executor : {"local", "dask"}
        A local process pool, or a Dask distributed cluster.
    scheduler : str, optional
        Dask scheduler address ``HOST:PORT``; a LocalCluster of `jobs` workers when None.
    out_dir : str or Path
        Output root; files go to ``out_dir/<study>/``.
    cache_dir : str or Path, optional
        Stage cache folder; None: $SEADESIGN_CACHE, else ~/.cache/seadesign.
    tolerance_mm : float
        STL chordal tolerance (mm).
    calibration : str or Path, optional
        Calibration JSON (from `explain`): the material it names takes the fitted law (`apply_calibration`);
        outputs go to ``out_dir/<study>-calibrated/``.

    Returns
    -------
    ExplorationResult
        The evaluated designs (``to_frame()``, ``plot()``), the decision and the files written.

    Raises
    ------
    ConfigError
        The study or the calibration is invalid (the message names the key) or `budget` is below 2.
    Interrupted
        A signal stopped it; finished evaluations are saved and a rerun resumes.

    Examples
    --------
    >>> import seadesign as sd
    >>> result = sd.run_exploration("wolfgang_knee", budget=12, jobs=2, quiet=True)
    >>> result.plot()
    """
    from seadesign.errors import ConfigError
    from seadesign.explore.explorer import ExplorerSettings
    from seadesign.explore.study_run import explore_study
    from seadesign.run.cache import default_cache
    from seadesign.run.executors import default_jobs
    from seadesign.sweep.stages import SolverSettings

    if budget < 2:
        raise ConfigError(f"budget must be at least 2 full-path evaluations, got {budget}")
    study = study if isinstance(study, Study) else load_study(study)
    note = ""
    if calibration is not None:
        from seadesign.sweep.pipeline import apply_calibration

        study, note = apply_calibration(study, calibration)
    cache = default_cache(cache_dir)
    solver = SolverSettings()
    folder = Path(out_dir) / (f"{study.name}-calibrated" if calibration is not None else study.name)
    explorer = ExplorerSettings(budget=budget, batch=batch or jobs or default_jobs(), seed=seed)
    run = explore_study(study, folder, explorer, solver=solver, cache=cache, executor=executor, jobs=jobs,
                        scheduler=scheduler, quiet=quiet)
    written = write_exploration_outputs(study, run, folder, solver, cache, tolerance_mm)
    if calibration is not None:
        note += "\n" + uncalibrated_choice_text(study, Path(out_dir) / study.name, run, folder, solver, cache)
    return ExplorationResult(study, run, folder, written, note)


def write_exploration_outputs(study: Study, run, folder: Path, solver, cache, tolerance_mm: float) -> dict[str, list[Path]]:
    """The exploration's tables, figures, render and report (`report.exploration`), and the chosen design's
    spring.json and CAD files (`sweep.handoff`, `sweep.outputs`); paths by kind."""
    from seadesign.report.exploration import headline, write_exploration
    from seadesign.report.explore_plots import column_label
    from seadesign.sweep.handoff import write_handoff
    from seadesign.sweep.outputs import chosen_path, export_cad

    decision, evaluated = run.decision, run.exploration.evaluated
    row = None if decision.index is None else evaluated.loc[decision.index]
    written = write_exploration(study, run.problem, run.exploration, decision, run.sobol, folder, run.settings,
                                None if row is None else chosen_path(study, row, solver, cache))
    if row is not None:
        objective = run.problem.objectives[0]
        selection = {"meets_requirements": decision.feasible, "conditional": bool(row["conditional"]),
                     "failed_constraints": str(row["failed_constraints"]), "not_judged": str(row["not_judged"]),
                     "deciding_objective": study.requirements.objectives[0], "rank": 1,
                     "explanation": headline(evaluated, decision, column_label(objective), objective)}
        written["spring"] = [write_handoff(study, evaluated, row, folder, run.settings, selection)]
        written["cad"] = export_cad(study, evaluated.loc[[decision.index]], folder, tolerance_mm, cache)
    return written


def uncalibrated_choice_text(study: Study, uncalibrated: Path, run, folder: Path, solver, cache) -> str:
    """The uncalibrated exploration's choice (its spring.json in `uncalibrated`) beside the calibrated one, each
    judged with the calibrated material: the old design is evaluated once more (`sweep.runner.run_candidates`)."""
    import json

    from seadesign.sweep.rank import rank
    from seadesign.sweep.runner import run_candidates

    old = uncalibrated / "spring.json"
    if not old.exists():
        return (f"no uncalibrated exploration in {uncalibrated} to compare with: run `seadesign explore {study.name}` "
                f"without --calibration first")
    design = study.candidate_of(json.loads(old.read_text()))
    rows = run_candidates(study, [design], folder / "uncalibrated_choice", settings=solver, cache=cache, quiet=True).rows
    judged = rank(rows, study)[0].iloc[0]

    def verdict(feasible: bool, misses: str) -> str:
        return "meets every requirement" if feasible else f"misses {misses}"

    lines = [f"  uncalibrated choice, calibrated material: {design.name}: "
             f"{verdict(bool(judged['feasible']), str(judged['failed_constraints']))}"]
    if run.decision.index is not None:
        row = run.exploration.evaluated.loc[run.decision.index]
        lines.append(f"  calibrated choice: {row['candidate']}: "
                     f"{verdict(bool(row['feasible']), str(row.get('failed_constraints', '')))}")
    return "\n".join(["calibration: the choice without and with it, each judged with the calibrated material:", *lines])
