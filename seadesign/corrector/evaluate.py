"""Open-loop evaluation on recordings: each corrector sees the recorded inputs step by step
(through the same online path it would use on the robot) and its command at t is compared with
the task's label (motor position at t+1, or the command sent at t for task "command"), on the
held-out rows of a split.

Metrics per knee and pooled, in rad: MSE (rad^2), MAE, MAPE (% of |motor position|), peak |error|;
plus MSE in the thesis's normalised units (positions / pi) for comparison with its tables.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from seadesign.corrector.dataset import KNEES, CorrectorDataset, Recording
from seadesign.corrector.modalities import channels, MODALITIES
from seadesign.corrector.runtime import Corrector

ALL = channels(tuple(MODALITIES))


def run_open_loop(corrector: Corrector, rec: Recording, task: str) -> dict[str, np.ndarray]:
    """Commands for every step t < T-1 of `rec` (robot frame, rad), per knee; index = step t.

    The target follows `task` ("thesis": Hall position at t; otherwise at t+1); a trained
    corrector uses the task it was trained for.
    """
    spec = getattr(corrector, "spec", None)
    task = spec.task if spec is not None else task
    corrector.reset()
    dt = np.diff(rec.time_s, prepend=rec.time_s[0])
    out = {}
    for knee in KNEES:
        ch = rec.knees[knee]
        table = np.column_stack([ch[c] for c in ALL])
        hall = ch["hall_pos_rad"]
        cmd = np.empty(len(rec.time_s) - 1)
        for t in range(len(cmd)):
            measured = dict(zip(ALL, table[t].tolist()))
            target = hall[t] if task == "thesis" else hall[t + 1]
            cmd[t] = corrector.command(knee, float(target), measured, float(dt[t]))
        out[knee] = cmd
    return out


def metrics(err: np.ndarray, truth: np.ndarray) -> dict[str, float]:
    """MSE (rad^2), MAE (rad), MAPE (%), peak |error| (rad), MSE of positions / pi (thesis units, (rad/pi)^2)."""
    mse = float(np.mean(err ** 2))
    return {"n_samples": int(len(err)), "mse_rad2": mse, "mae_rad": float(np.mean(np.abs(err))),
            "mape_pct": float(100 * np.mean(np.abs(err) / np.maximum(np.abs(truth), 1e-6))),
            "peak_rad": float(np.max(np.abs(err))), "mse_norm_pi2": mse / np.pi ** 2}


def open_loop_table(correctors: list[Corrector], recordings: list[Recording], ds: CorrectorDataset,
                    rows: np.ndarray, split_name: str) -> tuple[pd.DataFrame, dict[str, dict]]:
    """One table: every corrector x (left, right, both) on the dataset rows `rows` (held-out set).

    Also returns, per corrector, the command and truth arrays on those rows (for plots).
    """
    rec_of, knee_of, step_of = ds.recording[rows], ds.knee[rows], ds.step[rows]
    truth = ds.y[rows] * ds.sign[rows]  # the task's label in the robot frame
    table, traces = [], {}
    for c in correctors:
        runs = [run_open_loop(c, rec, ds.spec.task) for rec in recordings]
        pred = np.array([runs[r][KNEES[k]][s] for r, k, s in zip(rec_of, knee_of, step_of)])
        traces[c.name] = {"pred": pred, "truth": truth, "recording": rec_of, "knee": knee_of, "step": step_of}
        for label, mask in (("left", knee_of == 0), ("right", knee_of == 1), ("both", np.ones(len(rows), bool))):
            if mask.any():
                table.append({"candidate": c.name, "knee": label, **metrics(pred[mask] - truth[mask], truth[mask]),
                              "split": split_name, "task": ds.spec.task})
    return pd.DataFrame(table), traces
