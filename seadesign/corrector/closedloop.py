"""Closed-loop evaluation in the knee simulator: each corrector drives the simulated knees through
the thesis's protocol (6 directions x 3 speeds, hanging or on the ground) and is scored on the
Hall error (Hall reading - walk target, rad).

Tables: the table-6.1 analogue (mean absolute Hall error over all trials, best and worst trial)
and the table-6.2 analogue (peak absolute error), plus flags:

- ``unstable``: the corrector produced a non-finite command, its command left the target by
  more than `UNSTABLE_COMMAND_RAD`, or the Hall reading left +-`UNSTABLE_HALL_RAD` (the run
  stops there); a large but bounded error (e.g. the spring's sag on the ground) is not instability;
- ``oscillating``: while the target is at rest (the trials' standing phases, from `REST_SETTLE_S`
  after the trial starts), the command's correction (command - target) carries chatter: its part
  above a `CHATTER_WINDOW_S` moving average has an RMS above `CHATTER_RMS_RAD` in some trial
  (sensor noise passed through a PI gives far less). Judged at rest because there a correction
  has nothing to follow: a feed-forward's command is still, while a loop that oscillates keeps
  chattering. While walking, a feed-forward's correction carries the gait's own high harmonics
  (the dynamics it cancels), so chatter there is no sign of oscillation.

The thesis's 0.103 rad "command offset" correction is not applied: the simulator's target is
the position the knee should reach. Correctors that need IMU or foot-pressure inputs cannot be
driven (the simulator's observation holds only the knee channels) and are refused. A corrector with
`preview_steps` > 0 also gets the walk engine's next targets and the leg's load share (`Preview`).
"""

from __future__ import annotations

import copy
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd

from seadesign.corrector.dataset import KNEES
from seadesign.corrector.modalities import FIELD_CHANNELS, IMU_CHANNELS, PRESSURE_CHANNELS
from seadesign.corrector.reference import Preview
from seadesign.corrector.runtime import Corrector
from seadesign.errors import ConfigError, SeadesignError
from seadesign.twin import KneeSession, Trial, thesis_protocol
from seadesign.twin.knee import Observation

UNSTABLE_COMMAND_RAD = 1.5
UNSTABLE_HALL_RAD = np.pi
CHATTER_WINDOW_S = 0.1
CHATTER_RMS_RAD = 0.02
REST_SETTLE_S = 0.2
_ABSENT = dict.fromkeys(IMU_CHANNELS + PRESSURE_CHANNELS, float("nan"))


@dataclass
class ClosedLoopRun:
    """Logged arrays (n_trials, n_steps, 2) in the robot frame: target, hall, command (rad), effort (Nm); flags."""

    name: str
    rate_hz: float
    trials: list[Trial]
    target: np.ndarray
    hall: np.ndarray
    command: np.ndarray
    effort: np.ndarray
    unstable: bool
    oscillating: bool
    note: str = ""
    recording: pd.DataFrame | None = None  # robot-format table of the samples run (all, or those before a stop)


def needs_aux(corrector: Corrector) -> bool:
    """True for a corrector that reads IMU or foot-pressure channels (the knee simulator has none)."""
    spec = getattr(corrector, "spec", None)
    return spec is not None and any(m in ("imu", "pressure") for m in spec.modalities)


class Driver:
    """One independent copy of a corrector per trial of a session; `commands(obs)` asks every copy for its
    command (robot frame, (n_trials, 2) rad) from the observation and, when it previews, the walk engine's
    next targets and load share."""

    def __init__(self, corrector: Corrector, sim: KneeSession) -> None:
        if needs_aux(corrector):
            raise SeadesignError(f"corrector '{corrector.name}' needs IMU/foot-pressure inputs, which the knee "
                                 "simulator does not observe; train it on knee channels only for closed-loop use")
        self.sim, self.copies = sim, []
        for _ in range(sim.n_trials):
            c = copy.deepcopy(corrector)
            c.reset()
            self.copies.append(c)
        self.ahead = getattr(corrector, "preview_steps", 0)
        self.load = sim.stance * float(sim.ground)

    def commands(self, obs: Observation) -> np.ndarray:
        sim, t, ahead = self.sim, obs.step, self.ahead
        cmd = np.empty((sim.n_trials, 2))
        for i, c in enumerate(self.copies):
            for k, knee in enumerate(KNEES):
                measured = {dst: float(getattr(obs, src)[i, k]) for src, dst in FIELD_CHANNELS.items()}
                extra = {"preview": Preview(sim.target[i, t + 1: t + 1 + ahead, k], self.load[i, t: t + 1 + ahead, k])} \
                    if ahead else {}
                cmd[i, k] = c.command(knee, float(obs.target[i, k]), {**measured, **_ABSENT}, sim.dt, **extra)
        return cmd


def run_closed_loop(corrector: Corrector, spring: dict[str, Any], trials: list[Trial] | None = None,
                    ground: bool = False, rate_hz: float = 100.0, seed: int = 0, **session: Any) -> ClosedLoopRun:
    """Drive a KneeSession with `corrector` (one independent copy per trial); log and flag the run."""
    trials = trials if trials is not None else thesis_protocol()
    sim = KneeSession(spring, trials, ground=ground, rate_hz=rate_hz, seed=seed, **session)
    driver = Driver(corrector, sim)
    shape = (sim.n_trials, sim.n_steps, 2)
    target, hall, command, effort = (np.full(shape, np.nan) for _ in range(4))
    obs, unstable, note = sim.observe(), False, ""
    while obs is not None:
        cmd = driver.commands(obs)
        target[:, obs.step], hall[:, obs.step], command[:, obs.step] = obs.target, obs.hall_pos, cmd
        effort[:, obs.step] = obs.knee_eff
        if not np.isfinite(cmd).all() or np.abs(cmd - obs.target).max() > UNSTABLE_COMMAND_RAD \
                or np.abs(obs.hall_pos).max() > UNSTABLE_HALL_RAD:
            unstable = True
            note = f"stopped at step {obs.step} ({obs.time_s:.2f} s): command or Hall reading out of bounds"
            break
        try:
            obs = sim.step(cmd)
        except ConfigError as exc:
            unstable, note = True, f"simulator refused the command at step {obs.step}: {exc}"
            break
    table = sim.recording(partial=True) if sim.n_logged >= 2 else None
    return ClosedLoopRun(corrector.name, rate_hz, trials, target, hall, command, effort, unstable,
                         _nanmax(chatter_rms(command, target, rate_hz)) > CHATTER_RMS_RAD, note, table)


def _nanmax(x: np.ndarray) -> float:
    """Largest finite value, 0 when there is none (a run stopped before any rest)."""
    return float(np.nanmax(x)) if np.isfinite(x).any() else 0.0


def chatter_rms(command: np.ndarray, target: np.ndarray, rate_hz: float) -> np.ndarray:
    """Per trial and knee (rad): RMS of (command - target) minus its `CHATTER_WINDOW_S` moving average,
    over the samples where the target is at rest (NaN where a trial has none)."""
    corr = command - target
    n = max(3, int(round(CHATTER_WINDOW_S * rate_hz)) | 1)
    kernel = np.ones(n) / n
    settle = int(round(REST_SETTLE_S * rate_hz))
    out = np.full(corr.shape[::2], np.nan)
    for i in range(corr.shape[0]):
        for k in range(corr.shape[2]):
            x, tgt = corr[i, :, k], target[i, :, k]
            m = int(np.isfinite(x).sum())
            if m <= n:
                continue
            hf = x[n // 2: m - n // 2] - np.convolve(x[:m], kernel, mode="valid")
            still = np.convolve(np.abs(np.diff(tgt[:m], prepend=tgt[0])) < 1e-9, kernel, mode="valid") > 1 - 1e-9
            still &= np.arange(n // 2, m - n // 2) >= settle
            if still.any():
                out[i, k] = float(np.sqrt(np.mean(hf[still] ** 2)))
    return out


def trial_label(t: Trial) -> str:
    """'direction (speed)' as in the thesis's tables."""
    return f"{t.direction} ({t.speed:g})"


def summary_row(run: ClosedLoopRun, setting: str) -> dict[str, Any]:
    """Table 6.1 / 6.2 analogue row: mean |Hall error| overall, best and worst trial, peak, flags."""
    err = np.abs(run.hall - run.target)
    per_trial = np.nanmean(err, axis=(1, 2))
    worst, best = int(np.nanargmax(per_trial)), int(np.nanargmin(per_trial))
    return {"candidate": run.name, "setting": setting, "mean_abs_error_rad": float(np.nanmean(err)),
            "worst_trial": trial_label(run.trials[worst]), "worst_mean_abs_error_rad": float(per_trial[worst]),
            "best_trial": trial_label(run.trials[best]), "best_mean_abs_error_rad": float(per_trial[best]),
            "peak_abs_error_rad": float(np.nanmax(err)),
            "left_mean_abs_error_rad": float(np.nanmean(err[..., 0])),
            "right_mean_abs_error_rad": float(np.nanmean(err[..., 1])),
            "rest_chatter_rms_max_rad": _nanmax(chatter_rms(run.command, run.target, run.rate_hz)),
            "unstable_flag": run.unstable, "oscillating_flag": run.oscillating, "note": run.note}


def closed_loop_table(correctors: list[Corrector], spring: dict[str, Any], settings: tuple[str, ...] = ("hanging",),
                      trials: list[Trial] | None = None, rate_hz: float = 100.0, seed: int = 0,
                      **session: Any) -> tuple[pd.DataFrame, list[ClosedLoopRun]]:
    """Every corrector through the protocol in each setting ("hanging", "ground"); one row each."""
    rows, runs = [], []
    for setting in settings:
        if setting not in ("hanging", "ground"):
            raise SeadesignError(f"unknown closed-loop setting '{setting}'; use hanging or ground")
        for c in correctors:
            if needs_aux(c):
                rows.append({"candidate": c.name, "setting": setting, "note": "not run: needs IMU/pressure inputs"})
                continue
            run = run_closed_loop(c, spring, trials, ground=setting == "ground", rate_hz=rate_hz, seed=seed, **session)
            runs.append(run)
            rows.append(summary_row(run, setting))
    return pd.DataFrame(rows), runs
