"""The reference network: a feed-forward network trained on iterative-learning-control labels.

Labels: `ilc.learn_commands` in the knee simulator, for every walk direction at speeds that are
not the thesis protocol's (so the protocol stays unseen), hanging and on the ground, and for the
spring's stiffness scaled by each of `k_scales` (the network sees k, so it learns how the command
depends on it). Inputs: `reference.reference_features` (the reference window, load share, k);
no measured state. Output: the command (rad, flexion), as target + a learned correction.
Validation: whole trials held out (every `val_every`-th), early stopping as in `train.fit`.
"""

from __future__ import annotations

import time
from dataclasses import asdict, dataclass, field, replace
from typing import Any

import numpy as np
import torch

from seadesign.corrector.ilc import ILCResult, ILCSettings, learn_commands
from seadesign.corrector.reference import ReferenceWindow, reference_features
from seadesign.corrector.splits import Split
from seadesign.corrector.train import TrainConfig, TrainResult, fit_arrays
from seadesign.errors import SeadesignError
from seadesign.twin import Trial
from seadesign.twin.config import KneeConfig, knee_effects
from seadesign.twin.walk import DIRECTIONS, Gait

#: walk speeds of the ILC labels (m/s): around and between the protocol's 0.05 / 0.1 / 0.2, none equal
TRAIN_SPEEDS = (0.03, 0.075, 0.15, 0.25)
#: stiffness scales the simulator is trained at (1): inside the robustness range 0.7-1.4 (`goal.robustness_cases`)
TRAIN_K_SCALES = (0.8, 1.0, 1.25)


@dataclass(frozen=True)
class ImitationSettings:
    """What the labels cover and how the network is trained (speeds m/s, trial_s s, rate_hz Hz)."""

    window: ReferenceWindow = ReferenceWindow()
    speeds: tuple[float, ...] = TRAIN_SPEEDS
    conditions: tuple[str, ...] = ("hanging", "ground")  # the leg hanging, the foot on the ground
    k_scales: tuple[float, ...] = TRAIN_K_SCALES
    trial_s: float = 10.0
    rate_hz: float = 100.0
    gait: Gait = Gait()
    ilc: ILCSettings = ILCSettings()
    # one thread: the 3 x 64 network is too small to gain from two, and loses 10x when the CPU is shared
    train: TrainConfig = field(default_factory=lambda: TrainConfig(model="mlp", batch_size=4096, patience=20, threads=1))
    val_every: int = 5

    def trials(self) -> list[Trial]:
        return [Trial(d, s, self.trial_s) for d in DIRECTIONS for s in self.speeds]

    def to_dict(self) -> dict[str, Any]:
        d = asdict(self)
        d["train"] = asdict(self.train)
        return d


@dataclass
class ImitationResult:
    """The trained network, its labels (one ILCResult per setting and k scale) and the training record."""

    training: TrainResult
    labels: list[ILCResult]
    settings: ImitationSettings
    k_Nm_per_rad: float
    label_s: float

    def summary(self) -> dict[str, Any]:
        return {"settings": self.settings.to_dict(), "k_Nm_per_rad": self.k_Nm_per_rad,
                "label_s": round(self.label_s, 2), "training": self.training.summary(),
                "labels": [{"ground": r.ground, "k_Nm_per_rad": r.k_Nm_per_rad, "iterations": len(r.mean_abs_error_rad),
                            "best_iteration": r.best_iteration, "mean_abs_error_rad": r.mean_abs_error_rad}
                           for r in self.labels]}


def ilc_labels(spring: dict, settings: ImitationSettings) -> list[ILCResult]:
    """ILC on the training trials for every setting and k scale; refuses a batch that did not converge."""
    base = KneeConfig.from_spring(spring)
    out = []
    for setting in settings.conditions:
        ground = setting == "ground"
        for scale in settings.k_scales:
            config = replace(base, k_Nm_per_rad=base.k_Nm_per_rad * scale)
            chain = knee_effects(base, ground)
            if scale != 1.0:
                chain = chain.configure("stiffness_scale", enabled=True, scale=scale)
            res = learn_commands(spring, settings.trials(), ground=ground, rate_hz=settings.rate_hz,
                                 gait=settings.gait, config=config, effects=chain, settings=settings.ilc)
            if not res.converged:
                raise SeadesignError(
                    f"ILC did not reach its plateau in {settings.ilc.max_iterations} iterations ({setting}, "
                    f"k x {scale:g}; mean |error| {res.mean_abs_error_rad[-1]:.4g} rad); raise max_iterations")
            out.append(res)
    return out


def label_arrays(labels: list[ILCResult], window: ReferenceWindow) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Inputs (N, d), commands (N,) rad and a trial id per row (unique over all batches)."""
    X, y, group, offset = [], [], [], 0
    for r in labels:
        feats = reference_features(np.moveaxis(r.target_rad, 2, 1), np.moveaxis(r.load_share, 2, 1),
                                   r.k_Nm_per_rad, window)  # (trial, knee, step, d)
        X.append(feats.reshape(-1, feats.shape[-1]))
        y.append(np.moveaxis(r.command_rad, 2, 1).ravel())
        n_trials, n_steps = r.target_rad.shape[:2]
        group.append(np.repeat(offset + np.arange(n_trials), 2 * n_steps))
        offset += n_trials
    return np.concatenate(X), np.concatenate(y), np.concatenate(group)


def train_imitation(spring: dict, settings: ImitationSettings = ImitationSettings()) -> ImitationResult:
    """Labels by ILC, then the network; validation on whole held-out trials."""
    t0 = time.perf_counter()
    labels = ilc_labels(spring, settings)
    label_s = time.perf_counter() - t0
    X, y, group = label_arrays(labels, settings.window)
    trial_of_batch = group % len(settings.trials())
    val = np.flatnonzero(trial_of_batch % settings.val_every == settings.val_every - 1)
    train = np.setdiff1d(np.arange(len(y)), val)
    w = torch.zeros(X.shape[1])
    w[0] = 1.0  # command = target + learned correction
    result = fit_arrays(X, y, Split("held_out_trials", train, val, val), w, settings.train)
    return ImitationResult(result, labels, settings, float(spring["k_Nm_per_rad"]), label_s)
