"""Family-2 training benchmark: a corrector trained through the closed loop in the torch knee.

Trains from scratch and, with a family-1 network, fine-tuned; prints per run the wall time to the stop rule
(`closedloop_training`: validation mean |Hall error| not 1 % below its best for `patience` epochs), the epochs,
the simulated steps per second (one step = one 10 ms sample of the whole batch: training and validation trials x
hanging/ground x 2 knees; the no-gradient passes and the BPTT windows together, and the BPTT windows alone),
and the runtime's latency per control step (median). With --evaluate, the closed-loop goal table (per cell)
against none / PI / k-feed-forward and family 1 in the knee simulator: the thesis protocol (nominal), a held-out
gait (cycle 0.7 s) and the spring's k scaled by 0.7 and 1.4.

    python benchmarks/train_closedloop.py [--family1 /tmp/family1.pt] [--evaluate] [--threads 1]

--family1: a family-1 `CorrectorNet` saved with torch.save; trained with `train_imitation` (about 6 min) and saved
there when the file does not exist. Without it only the from-scratch run is made.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import platform
import time
from pathlib import Path

import numpy as np
import pandas as pd
import torch

from seadesign import __version__
from seadesign.design.spring import load_spring
from seadesign.corrector.closedloop import closed_loop_table
from seadesign.corrector.closedloop_training import ClosedLoopCorrector, ClosedLoopSettings, train_closed_loop
from seadesign.corrector.export import NumpyCorrector, numpy_arrays
from seadesign.corrector.goal import goal_table
from seadesign.corrector.imitation import ImitationSettings, train_imitation
from seadesign.corrector.reference import Preview
from seadesign.corrector.runtime import FeedForward, HallPI, NoCorrection, ReferenceFeedForward
from seadesign.twin import Gait, KneeConfig, knee_effects

SPRING = load_spring(Path(__file__).resolve().parents[1] / "studies" / "thesis_measured_spring.json")
CASES = {"nominal": {}, "gait 0.7 s": {"gait": Gait(cycle_s=0.7)}, "k x0.7": {"k_scale": 0.7},
         "k x1.4": {"k_scale": 1.4}}


def _latency_us(corrector, calls: int) -> float:
    """Median wall time of one `command` call (us), walking target, left knee."""
    preview = Preview(np.linspace(1.0, 1.1, corrector.preview_steps), np.full(corrector.preview_steps + 1, 0.5))
    measured = {"hall_pos_rad": 0.98, "hall_vel_rad_per_s": 0.2}
    corrector.reset()
    times = np.empty(calls)
    for i in range(calls):
        t0 = time.perf_counter()
        corrector.command("left", 1.0 + 1e-4 * i, measured, 0.01, preview)
        times[i] = time.perf_counter() - t0
    return float(np.median(times) * 1e6)


def _family1(path: Path | None) -> torch.nn.Module | None:
    if path is None:
        return None
    if not path.exists():
        t0 = time.perf_counter()
        net = train_imitation(SPRING, ImitationSettings()).training.net
        torch.save(net, path)
        print(f"family 1 trained in {time.perf_counter() - t0:.0f} s, saved to {path}", flush=True)
    return torch.load(path, weights_only=False)


def _evaluate(correctors: list, names: list[str]) -> pd.DataFrame:
    """Goal table summary per case and setting for each candidate in `names`."""
    k = SPRING["k_Nm_per_rad"]
    cfg = KneeConfig.from_spring(SPRING)
    rows = []
    for case, options in CASES.items():
        for setting in ("hanging", "ground"):
            session = {key: v for key, v in options.items() if key != "k_scale"}
            if "k_scale" in options:
                session["effects"] = knee_effects(cfg, ground=setting == "ground").configure(
                    "stiffness_scale", enabled=True, scale=options["k_scale"])
            table, runs = closed_loop_table([NoCorrection(), HallPI(), FeedForward(k), *correctors], SPRING,
                                            (setting,), **session)
            by_name = table.set_index("candidate")
            for name in names:
                g = goal_table({setting: runs}, name)
                rows.append({"case": case, "setting": setting, "candidate": name,
                             "mean_abs_error_rad": by_name.loc[name, "mean_abs_error_rad"],
                             "cells_met": f"{int(g.meets_goal.sum())}/{len(g)}", "gain_min": g.gain.min(),
                             "gain_median": g.gain.median(),
                             "rest_chatter_max_rad": by_name.loc[name, "rest_chatter_rms_max_rad"],
                             "flagged": bool(g.flagged.any())})
            print(f"evaluated {case}, {setting}", flush=True)
    return pd.DataFrame(rows)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--family1", type=Path, default=None, help="family-1 network (torch.save); trained if absent")
    ap.add_argument("--evaluate", action="store_true", help="closed-loop goal tables in the knee simulator")
    ap.add_argument("--threads", type=int, default=1, help="torch intra-op threads for training")
    ap.add_argument("--calls", type=int, default=3000, help="runtime latency: command calls timed")
    args = ap.parse_args()
    print(f"machine: {platform.node()} {platform.machine()}, {os.cpu_count()} cores, {platform.processor() or '?'}; "
          f"python {platform.python_version()}, torch {torch.__version__}, numpy {np.__version__}, "
          f"seadesign {__version__}")
    family1 = _family1(args.family1)
    base = ClosedLoopSettings(threads=args.threads)
    runs = {"scratch": (base, None)}
    if family1 is not None:
        runs["fine-tuned"] = (dataclasses.replace(base, lr=1e-3), family1)
    knees = len(base.directions) * (len(base.speeds) + len(base.val_speeds)) * len(base.settings) * 2
    print(f"settings: {len(base.directions)} directions x speeds {base.speeds} (training) and {base.val_speeds} "
          f"(validation), {base.trial_s:g} s trials, {' and '.join(base.settings)}, noise on, float64 knee; windows "
          f"of {base.window_steps} samples, feedback Lipschitz bound {base.lipschitz_rad_per_rad} rad/rad, command-"
          f"rate weight {base.rate_weight_s2:g} s^2; stop: < {base.min_improvement:.0%} for {base.patience} epochs "
          f"(cap {base.max_seconds:g} s); threads {args.threads}; batch {knees} knees (steps/s: samples of the batch)")
    print(f"{'run':<11} {'lr':>6} {'epochs':>6} {'best':>5} {'stop':>10} {'wall_s':>7} {'steps/s':>8} "
          f"{'bptt steps/s':>12} {'val_err_rad':>11} {'L_bound':>7} {'step_us':>7}")
    correctors, names = [], []
    if family1 is not None:
        f1 = ReferenceFeedForward(NumpyCorrector(numpy_arrays(family1)), base.window, SPRING["k_Nm_per_rad"],
                                  name="family1")
        correctors.append(f1)
        names.append("family1")
    for name, (settings, init) in runs.items():
        res = train_closed_loop(SPRING, settings, init)
        bptt_s = sum(row["bptt_s"] for row in res.curve)
        corrector = ClosedLoopCorrector(res.policy, SPRING["k_Nm_per_rad"], name=f"family2 {name}")
        print(f"{name:<11} {settings.lr:>6g} {len(res.curve) - 1:>6} {res.best_epoch:>5} {res.stopped:>10} "
              f"{res.wall_s:>7.1f} {res.simulated_steps / res.wall_s:>8.0f} {res.trained_steps / bptt_s:>12.0f} "
              f"{res.curve[res.best_epoch]['val_mean_abs_error_rad']:>11.4f} "
              f"{res.policy.feedback_lipschitz_bound():>7.3f} {_latency_us(corrector, args.calls):>7.1f}", flush=True)
        correctors.append(corrector)
        names.append(corrector.name)
    if family1 is not None:
        print(f"family 1 runtime step: {_latency_us(correctors[0], args.calls):.1f} us")
    if args.evaluate:
        pd.set_option("display.width", 200)
        print(_evaluate(correctors, names).to_string(index=False, float_format=lambda v: f"{v:.4f}"))


if __name__ == "__main__":
    main()
