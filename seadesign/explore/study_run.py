"""A study explored end to end (without writing): the spring problem, the explorer, the decision, the Sobol
indices and the settings to record with the results."""

from __future__ import annotations

import time
from dataclasses import asdict, dataclass, replace
from pathlib import Path

import pandas as pd

from seadesign.design.study import Study
from seadesign.explore.decision import Decision, decide
from seadesign.explore.explorer import Exploration, ExplorerSettings, explore
from seadesign.explore.sensitivity import sobol_indices
from seadesign.explore.spring_problem import SpringProblem
from seadesign.run.cache import Cache
from seadesign.run.executors import default_jobs, keeping_workers
from seadesign.run.progress import ProgressDisplay
from seadesign.sweep.requirements import LOAD_CLASS, OBJECTIVE_WORDS, lacks_limit, requirement_list
from seadesign.sweep.runner import sweep_settings
from seadesign.sweep.stages import SolverSettings, check_geometry, coarse_k, part_source
from seadesign.sweep.table import k_error_columns


@dataclass
class StudyExploration:
    problem: SpringProblem
    exploration: Exploration
    decision: Decision
    sobol: pd.DataFrame
    settings: dict  # recorded with the results (study, solver, explorer, versions)
    wall_s: float


def not_judged_reasons(study: Study) -> dict[str, str]:
    """Why a strain margin may not be judged: a material without a sourced limit for the load's class."""
    out = {}
    for load in study.requirements.loads:
        missing = [m.name for m in study.materials.values() if lacks_limit(m, load)]
        if missing:
            out[f"{load}_strain_margin"] = f"no sourced {LOAD_CLASS[load][1]} for {', '.join(missing)}"
    return out


def explore_study(study: Study, out_dir: Path, explorer: ExplorerSettings, *, solver: SolverSettings = SolverSettings(),
                  cache: Cache | None = None, executor: str = "local", jobs: int | None = None,
                  scheduler: str | None = None, quiet: bool = False) -> StudyExploration:
    """Explore `study` within `explorer.budget` full evaluations (rows stored under `out_dir`, resumable)."""
    t0 = time.perf_counter()
    cache = cache or Cache()
    display = ProgressDisplay(explorer.budget, 0, {}, quiet)
    problem = SpringProblem(study, out_dir, replace(solver, k_error_estimate=False), cache, executor, jobs, scheduler,
                            display)
    with keeping_workers():
        exploration = explore(problem, explorer, jobs or default_jobs())
    display.close()
    words = {r.column: r.words for r in requirement_list(study)}
    decision = decide(exploration, problem.encoding, words, not_judged_reasons(study),
                      OBJECTIVE_WORDS[study.requirements.objectives[0]], explorer.seed)
    if decision.index is not None and solver.k_error_estimate:
        estimate_k_error(problem, exploration.evaluated, decision.index, solver)
    sobol = sobol_indices(problem.encoding, exploration.models, problem.outputs, explorer.seed)
    settings = sweep_settings(study, problem.settings)
    settings["solver"]["k_error_estimate"] = "the reported design only" if solver.k_error_estimate else False
    settings.update(requirements=asdict(study.requirements), explorer=asdict(explorer))
    return StudyExploration(problem, exploration, decision, sobol, settings, time.perf_counter() - t0)


def estimate_k_error(problem: SpringProblem, evaluated: pd.DataFrame, index, solver: SolverSettings) -> None:
    """k's discretization error of the reported design, which the evaluations skip: its coarse-k stage (`sweep.stages.
    coarse_k`, cached); the row's k-error columns are updated in place."""
    x = evaluated.loc[index, [f"x{i}" for i in range(len(problem.encoding.keys))]].to_numpy(float)
    (candidate, _), = problem.candidates(x)
    checked, part = check_geometry(problem.study, candidate, problem.cache)
    coarse = coarse_k(problem.study, checked, part_source(problem.study, checked, part, lambda _: None), solver,
                      problem.cache, lambda _: None)
    for column, value in k_error_columns(coarse, evaluated.loc[index, "k_Nm_per_rad"]).items():
        evaluated.loc[index, column] = value
