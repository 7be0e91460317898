"""How much an exploration costs and what it finds against its budget.

Prints the machine and settings, full-path evaluations used (geometry, mesh, linear and large-deflection
solve) and screenings (geometry and validity only) counted apart, wall time, and per round the evaluations
so far, the best feasible first objective and the least total violation. The goal (issue #16): the knee
study answered with at most 80 full-path evaluations in under 40 minutes on a 2-core machine.

`--elements-across-beam` and `--layers` override the study's [mesh] (a coarse mesh for a quick look; the
answer is only the answer at the study's own mesh). Cold by default (a fresh cache and output folder);
`--cache-dir` and `--out` reuse earlier work.

Usage: python benchmarks/explore.py [STUDY] [--budget N] [--jobs N] [--seed S]
"""

from __future__ import annotations

import argparse
import dataclasses
import tempfile
from pathlib import Path

from seadesign.design.study import load_study
from seadesign.explore.explorer import ExplorerSettings
from seadesign.explore.study_run import explore_study
from seadesign.run.cache import Cache
from seadesign.run.executors import default_jobs
from seadesign.sweep.stages import SolverSettings
from record import machine


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("study", nargs="?", default="wolfgang_knee_explore")
    ap.add_argument("--budget", type=int, default=80, help="full-path evaluations at most (count)")
    ap.add_argument("--jobs", type=int, default=default_jobs(), help="worker processes (count), also the batch size")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--elements-across-beam", type=float, default=None, help="override the study's mesh (count)")
    ap.add_argument("--layers", type=float, default=None, help="override the study's layers through the thickness")
    ap.add_argument("--cache-dir", type=Path, default=None, help="stage cache (default: a fresh temporary one)")
    ap.add_argument("--out", type=Path, default=None, help="output folder (default: a fresh temporary one)")
    args = ap.parse_args()
    study = load_study(args.study)
    mesh = study.mesh
    if args.elements_across_beam is not None:
        mesh = dataclasses.replace(mesh, elements_across_beam=args.elements_across_beam)
    if args.layers is not None:
        mesh = dataclasses.replace(mesh, layers=args.layers)
    study = dataclasses.replace(study, mesh=mesh)
    loop = ExplorerSettings(budget=args.budget, batch=args.jobs, seed=args.seed)
    solver = SolverSettings()
    with tempfile.TemporaryDirectory(prefix="seadesign-explore-") as tmp:
        cache = Cache(args.cache_dir or Path(tmp) / "cache")
        run = explore_study(study, args.out or Path(tmp) / "out", loop, solver=solver, cache=cache, jobs=args.jobs,
                            quiet=True)
    t, screened = run.exploration.evaluated, run.exploration.screened
    print(f"machine (at the end): {machine()}")
    print(f"settings: study {study.name}, mesh {dataclasses.asdict(mesh)}, solver {dataclasses.asdict(solver)}, "
          f"loop {dataclasses.asdict(loop)}")
    print(f"full-path evaluations: {len(t)} of {loop.budget}; screenings: {len(screened)} "
          f"({int((~screened['valid'].astype(bool)).sum())} invalid); wall {run.wall_s:.0f} s "
          f"({run.wall_s / 60:.1f} min); stop: {run.exploration.stop_reason}")
    objective = run.problem.objectives[0]
    print(f"{'round':>5} {'evaluations':>11} {'screenings':>10} {'best ' + objective:>18} {'least violation':>16}")
    for r in run.exploration.rounds:
        print(f"{r.index:>5} {r.evaluations:>11} {r.screenings:>10} {r.best_objective:>18.4g} {r.least_violation:>16.4g}")
    for o, e in run.exploration.models.loo_errors(run.problem.outputs).items():
        print(f"leave-one-out {o}: mean {100 * e.mean_abs_rel:.2f} %, largest {100 * e.max_abs_rel:.2f} % ({e.n} designs)")
    d = run.decision
    choice = "none" if d.index is None else t.loc[d.index, "candidate"]
    print(f"choice: {choice} ({'feasible' if d.feasible else 'infeasible'}); missed: "
          + ("; ".join(f"{w} by {-m:.1%}" for w, m in d.missed) or "nothing"))
    print(d.predicted)


if __name__ == "__main__":
    main()
