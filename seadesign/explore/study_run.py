"""A study explored end to end (without writing): the spring problem, the loop, the decision, the Sobol
indices and the settings to record with the results."""

from __future__ import annotations

import time
from dataclasses import asdict, dataclass, replace
from pathlib import Path

import pandas as pd

from seadesign.design.study import Study
from seadesign.errors import SolverError
from seadesign.explore.decision import Decision, decide
from seadesign.explore.loop import Exploration, LoopSettings, explore
from seadesign.explore.sensitivity import sobol_indices
from seadesign.explore.spring_problem import SpringProblem
from seadesign.run.cache import Cache
from seadesign.run.progress import ProgressDisplay
from seadesign.sweep.requirements import OBJECTIVE_WORDS, requirement_list
from seadesign.sweep.runner import run_candidates, sweep_settings
from seadesign.sweep.stages import SolverSettings


@dataclass
class StudyExploration:
    problem: SpringProblem
    exploration: Exploration
    decision: Decision
    sobol: pd.DataFrame
    settings: dict  # recorded with the results (study, solver, loop, versions)
    wall_s: float


def not_judged_reasons(study: Study) -> dict[str, str]:
    """Why a strain margin may not be judged: a material without a sourced elongation at yield."""
    missing = [m for m in study.materials.values() if m.elongation_at_yield is None]
    if not missing:
        return {}
    why = ("no allowable strain for " + ", ".join(m.name for m in missing)
           + " (its material file has no sourced elongation at yield)")
    return {f"{load}_strain_margin": why for load in study.requirements.loads}


def explore_study(study: Study, out_dir: Path, loop: LoopSettings, *, solver: SolverSettings = SolverSettings(),
                  cache: Cache = Cache(), executor: str = "local", jobs: int | None = None,
                  scheduler: str | None = None, quiet: bool = False) -> StudyExploration:
    """Explore `study` within `loop.budget` full evaluations (rows stored under `out_dir`, resumable)."""
    t0 = time.perf_counter()
    display = ProgressDisplay(loop.budget, 0, {}, quiet)
    problem = SpringProblem(study, out_dir, replace(solver, k_error_estimate=False), cache, executor, jobs, scheduler,
                            display)
    exploration = explore(problem, loop)
    display.close()
    words = {r.column: r.words for r in requirement_list(study)}
    decision = decide(exploration, problem.encoding, words, not_judged_reasons(study),
                      OBJECTIVE_WORDS[study.requirements.objectives[0]], loop.seed)
    if decision.index is not None and solver.k_error_estimate:
        estimate_k_error(problem, exploration.evaluated, decision.index, solver)
    sobol = sobol_indices(problem.encoding, exploration.models, problem.outputs, loop.seed)
    settings = {**sweep_settings(study, problem.settings), "requirements": asdict(study.requirements),
                "loop": asdict(loop), "k_error_estimate": "the reported design only"}
    return StudyExploration(problem, exploration, decision, sobol, settings, time.perf_counter() - t0)


K_ERROR_COLUMNS = ("k_coarse_Nm_per_rad", "k_rel_error", "time_error_estimate_s")


def estimate_k_error(problem: SpringProblem, evaluated: pd.DataFrame, index, solver: SolverSettings) -> None:
    """k's discretization error of the reported design, which the evaluations skip: its linear stage again with the
    coarse solve (its path comes from the cache); the row's K_ERROR_COLUMNS are updated in place."""
    x = evaluated.loc[index, [f"x{i}" for i in range(len(problem.encoding.keys))]].to_numpy(float)
    (candidate, _), = problem.candidates(x)
    row = run_candidates(problem.study, [candidate], problem.out_dir, settings=solver, cache=problem.cache,
                         executor="serial", quiet=True).rows.iloc[0]
    if row["status"] != "ok" or abs(row["k_Nm_per_rad"] / evaluated.loc[index, "k_Nm_per_rad"] - 1.0) > 1e-9:
        raise SolverError(f"{candidate.name}: the error-estimate run of the reported design did not reproduce its "
                          f"evaluation ({row['status']}: {row.get('reason', '')})")
    for column in K_ERROR_COLUMNS:
        evaluated.loc[index, column] = row[column]
