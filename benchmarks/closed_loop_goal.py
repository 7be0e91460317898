"""The closed-loop goal of a corrector bundle, cell by cell, nominal and in the robustness cases.

For each case (nominal thesis protocol; a gait with a 0.7 s cycle; k x0.7 and x1.4; real-knee effects; the
large-deflection law swapped) and setting: mean |Hall error| of the corrector and of the best baseline
(none, PI, k feed-forward), the smallest and median gain (1 - corrector / best baseline), the cells meeting
the goal, flags, loop-gain margin; and the wall time of the case.

    python benchmarks/closed_loop_goal.py BUNDLE --spring spring.json
"""

from __future__ import annotations

import argparse
import os
import platform
import time

import numpy as np

from seadesign.corrector.goal import Case, case_table, goal_table, robustness_cases
from seadesign.corrector.runtime import FeedForward, HallPI, NoCorrection
from seadesign.corrector.stability import measure_loop_gain
from seadesign.corrector.workflow import load_corrector
from seadesign.design.spring import load_spring, torque_curve
from seadesign.twin import Gait, thesis_protocol


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("bundle")
    ap.add_argument("--spring", required=True)
    args = ap.parse_args()
    spring = load_spring(args.spring)
    corrector, meta = load_corrector(args.bundle)
    k = spring["k_Nm_per_rad"]
    candidates = [NoCorrection(), HallPI(), FeedForward(k, torque_curve(spring)), corrector]
    print(f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores, load average "
          f"{os.getloadavg()[0]:.1f}; bundle {args.bundle} ({meta['name']}), spring {args.spring} (k {k:.4g} Nm/rad)")
    print(f"{'case':<18} {'setting':<8} {'mean_rad':>9} {'best_base_rad':>14} {'gain_min':>9} {'gain_med':>9} "
          f"{'goal_cells':>10} {'flagged':>8} {'margin':>7} {'wall_s':>7}")
    margin = {s: measure_loop_gain(corrector, spring, thesis_protocol()[::3], s == "ground").modulus_margin
              for s in ("hanging", "ground")}
    cases = [Case("nominal"), Case("gait 0.7 s cycle", gait=Gait(cycle_s=0.7)), *robustness_cases(spring)]
    for case in cases:
        t0 = time.perf_counter()
        _, runs = case_table(candidates, spring, case, ("hanging", "ground"), thesis_protocol())
        table = goal_table(runs, corrector.name)
        wall = time.perf_counter() - t0
        for setting, rows in table.groupby("setting", sort=False):
            print(f"{case.name:<18} {setting:<8} {rows.mean_abs_error_rad.mean():>9.4f} "
                  f"{rows.best_baseline_mean_abs_error_rad.mean():>14.4f} {rows.gain.min():>9.3f} "
                  f"{np.median(rows.gain):>9.3f} {f'{int(rows.meets_goal.sum())}/{len(rows)}':>10} "
                  f"{str(bool(rows.flagged.any())):>8} {margin[setting]:>7.2f} {wall:>7.0f}")
    print("gain: 1 - corrector / best baseline mean |Hall error| per cell (trial x setting); goal: >= 0.3, peak not "
          "above the best baseline's, no flag; margin: loop-gain modulus margin in the nominal simulator (6 trials).")


if __name__ == "__main__":
    main()
