"""A study explored end to end (without writing): the spring problem, the loop, the decision, the Sobol
indices and the settings to record with the results."""

from __future__ import annotations

import time
from dataclasses import asdict, dataclass
from pathlib import Path

import pandas as pd

from seadesign.design.study import Study
from seadesign.explore.decision import Decision, decide
from seadesign.explore.loop import Exploration, LoopSettings, explore
from seadesign.explore.sensitivity import sobol_indices
from seadesign.explore.spring_problem import SpringProblem
from seadesign.run.cache import Cache
from seadesign.run.progress import ProgressDisplay
from seadesign.sweep.requirements import OBJECTIVE_WORDS, requirement_list
from seadesign.sweep.runner import sweep_settings
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
    problem = SpringProblem(study, out_dir, solver, cache, executor, jobs, scheduler, display)
    exploration = explore(problem, loop)
    display.close()
    words = {r.column: r.words for r in requirement_list(study)}
    decision = decide(exploration, problem.encoding, words, not_judged_reasons(study),
                      OBJECTIVE_WORDS[study.requirements.objectives[0]], loop.seed)
    sobol = sobol_indices(problem.encoding, exploration.models, problem.outputs, loop.seed)
    settings = {**sweep_settings(study, solver), "requirements": asdict(study.requirements), "loop": asdict(loop)}
    return StudyExploration(problem, exploration, decision, sobol, settings, time.perf_counter() - t0)
