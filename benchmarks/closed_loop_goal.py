"""The closed-loop goal of one or more corrector bundles, cell by cell, nominal and in the robustness cases:
the fair comparison of the correctors (same cases, same baselines, one table).

For each case (`goal.goal_cases`: nominal thesis protocol; a gait with a 0.7 s cycle; k x0.7 and x1.4; real-knee
effects; the large-deflection law swapped), setting and bundle: mean |Hall error| of the corrector and of the best
baseline (none, PI, k feed-forward), the smallest and median gain (1 - corrector / best baseline), the cells
meeting the goal, the smallest share of the nominal gain kept per cell (robustness cases), flags, and the wall
time of the case (all candidates). Then per bundle the verdict over all cases (`goal.verdict`) and the winner
(`goal.winner`: meets the goal and is robust, with the lowest mean |Hall error| over cases and settings), and
its loop-gain modulus margin in the nominal simulator (6 trials).

    python benchmarks/closed_loop_goal.py BUNDLE [BUNDLE ...] --spring spring.json [--docs]

`--docs` writes the table per case, setting and bundle into docs/validation/_fragments/closed_loop_goal.md.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from record import Table, add_docs_option, machine, write_fragment

from seadesign.corrector.goal import case_table, goal_cases, goal_table, verdict, winner
from seadesign.corrector.runtime import FeedForward, HallPI, NoCorrection
from seadesign.corrector.stability import measure_loop_gain
from seadesign.corrector.workflow import load_corrector
from seadesign.design.spring import load_spring, torque_curve
from seadesign.twin import thesis_protocol


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("bundles", nargs="+")
    ap.add_argument("--spring", required=True)
    add_docs_option(ap, "closed_loop_goal")
    args = ap.parse_args()
    spring = load_spring(args.spring)
    loaded = [load_corrector(b) for b in args.bundles]
    correctors = [c for c, _ in loaded]
    names = [c.name for c in correctors]
    if len(set(names)) != len(names):
        raise SystemExit(f"bundle names must differ to share one table, got {names}")
    k = spring["k_Nm_per_rad"]
    candidates = [NoCorrection(), HallPI(), FeedForward(k, torque_curve(spring)), *correctors]
    docs = Table(["case", "setting", "bundle", "mean abs Hall error (rad)", "best baseline (rad)", "smallest gain",
                  "median gain", "cells meeting the goal", "smallest share of the nominal gain kept", "flagged",
                  "case wall time (s)"])
    print(f"machine: {machine()}; spring {args.spring} (k {k:.4g} Nm/rad); bundles: "
          + ", ".join(f"{b} ({m['name']})" for b, (_, m) in zip(args.bundles, loaded)))
    print(f"{'case':<18} {'setting':<8} {'candidate':<14} {'mean_rad':>9} {'best_base_rad':>14} {'gain_min':>9} "
          f"{'gain_med':>9} {'goal_cells':>10} {'kept_min':>8} {'flagged':>8} {'wall_s':>7}")
    goals: dict[str, dict] = {name: {} for name in names}
    for case in goal_cases(spring):
        t0 = time.perf_counter()
        _, runs = case_table(candidates, spring, case, ("hanging", "ground"), thesis_protocol())
        wall = time.perf_counter() - t0
        for name in names:
            table = goals[name][case.name] = goal_table(runs, name)
            share = table.gain.to_numpy() / goals[name]["nominal"].gain.to_numpy()
            for setting in ("hanging", "ground"):
                rows, kept = table[table.setting == setting], share[(table.setting == setting).to_numpy()]
                print(f"{case.name:<18} {setting:<8} {name:<14} {rows.mean_abs_error_rad.mean():>9.4f} "
                      f"{rows.best_baseline_mean_abs_error_rad.mean():>14.4f} {rows.gain.min():>9.3f} "
                      f"{np.median(rows.gain):>9.3f} {f'{int(rows.meets_goal.sum())}/{len(rows)}':>10} "
                      f"{kept.min():>8.2f} {str(bool(rows.flagged.any())):>8} {wall:>7.0f}", flush=True)
                docs.add(case.name, setting, name, f"{rows.mean_abs_error_rad.mean():.4f}",
                         f"{rows.best_baseline_mean_abs_error_rad.mean():.4f}", f"{rows.gain.min():.3f}",
                         f"{np.median(rows.gain):.3f}", f"{int(rows.meets_goal.sum())}/{len(rows)}", f"{kept.min():.2f}",
                         "yes" if rows.flagged.any() else "no", f"{wall:.0f}")
    print("gain: 1 - corrector / best baseline mean |Hall error| per cell (trial x setting); goal: >= 0.3, peak not "
          "above the best baseline's, no flag; kept_min: smallest gain / nominal gain per cell (robustness: >= 0.5).")
    verdicts = {name: verdict(goals[name]) for name in names}
    trials = thesis_protocol()[::3]
    print(f"{'candidate':<14} {'meets_goal':>10} {'robust':>7} {'kept_min':>8} {'mean_over_cases_rad':>19} "
          f"{'margin_hanging':>14} {'margin_ground':>13}")
    for c, name in zip(correctors, names):
        v = verdicts[name]
        margin = [measure_loop_gain(c, spring, trials, ground).modulus_margin for ground in (False, True)]
        print(f"{name:<14} {str(v['meets_goal']):>10} {str(v['robust']):>7} {v['kept_share_min']:>8.2f} "
              f"{v['mean_abs_error_rad']:>19.4f} {margin[0]:>14.2f} {margin[1]:>13.2f}")
    print(f"winner (meets the goal, robust, lowest mean |Hall error| over cases and settings): {winner(verdicts)}")
    if args.docs:
        write_fragment("closed_loop_goal", docs, f"Spring {args.spring} (k {k:.4g} Nm/rad); bundles "
                       + ", ".join(args.bundles) + "; cases of `corrector.goal.goal_cases`, hanging and ground",
                       "Gain: 1 - corrector / best baseline mean |Hall error| per cell (trial x setting); the goal: "
                       f">= 0.3, peak not above the best baseline's, no flag. Winner: {winner(verdicts)}.")


if __name__ == "__main__":
    main()
