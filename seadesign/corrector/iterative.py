"""Iterative training (thesis sec. 6.2.3 / 8.1): retrain on recordings collected with the current
corrector in the loop.

Round 0 trains on the given recordings (or, without any, on a simulated run with no correction).
Each round then drives the knee simulator through the protocol with the round's corrector, scores
it (closed-loop table row), cleans the simulated recording with the data module's steps and adds it
to the training pool for the next round. A run that goes unstable adds the samples recorded before
it stopped (the states the corrector drove the knee into are what the next round must learn).
"""

from __future__ import annotations

from typing import Any

import pandas as pd

from seadesign.corrector.closedloop import run_closed_loop, summary_row
from seadesign.corrector.dataset import DatasetSpec, Recording, build_dataset
from seadesign.corrector.export import NumpyCorrector, numpy_arrays
from seadesign.corrector.recordings import recording_from_table
from seadesign.corrector.runtime import NetCorrector, NoCorrection
from seadesign.corrector.splits import make_split
from seadesign.corrector.train import TrainConfig, TrainResult, fit
from seadesign.errors import SeadesignError
from seadesign.twin import Trial, thesis_protocol


def iterate(spring: dict[str, Any], recordings: list[Recording], spec: DatasetSpec, config: TrainConfig,
            rounds: int = 2, setting: str = "hanging", trials: list[Trial] | None = None,
            split: str = "time_blocks", seed: int = 0) -> tuple[pd.DataFrame, list[TrainResult]]:
    """Train, drive the simulator, add the run to the pool; `rounds` retraining rounds after round 0.

    Returns the closed-loop table with one row per round (plus the pool size and validation MSE)
    and the training results of every round.
    """
    if rounds < 0:
        raise SeadesignError(f"rounds must be >= 0, got {rounds} (--rounds)")
    trials = trials if trials is not None else thesis_protocol()
    ground = setting == "ground"
    k = float(spring["k_Nm_per_rad"])
    pool = list(recordings)
    if not pool:
        start = run_closed_loop(NoCorrection(), spring, trials, ground=ground, seed=seed)
        pool.append(recording_from_table(start.recording, "sim_no_correction")[0])
    rows, results = [], []
    for r in range(rounds + 1):
        ds = build_dataset(pool, spec)
        res = fit(ds, make_split(ds, split, seed=config.seed), k, config)
        results.append(res)
        net = NetCorrector(NumpyCorrector(numpy_arrays(res.net)), spec, f"{config.model} round {r}")
        run = run_closed_loop(net, spring, trials, ground=ground, seed=seed + r + 1)
        rows.append({"round": r, "n_recordings": len(pool), "n_samples": len(ds),
                     "val_mse_rad2": res.summary()["best_val_mse_rad2"],
                     "recorded_s": 0.0 if run.recording is None else len(run.recording) / run.rate_hz,
                     **summary_row(run, setting)})
        if run.recording is None:  # stopped before two samples: nothing to add
            break
        pool.append(recording_from_table(run.recording, f"sim_round_{r}")[0])
    return pd.DataFrame(rows), results
