"""The closed-loop policy (`closedloop_policy`) trained through the closed loop, in the differentiable knee
(`twin.torch_knee`).

Training (`train_closed_loop`): the training trials (every walk direction at `imitation.TRAIN_SPEEDS`,
not the protocol's speeds) and the validation trials (every direction at `VAL_SPEEDS`) run hanging and
on the ground, each with the spring's stiffness scaled by every one of `k_scales` (`imitation.TRAIN_K_SCALES`,
0.8 / 1 / 1.25), in one batched torch knee (the ground chain; a hanging trial carries no stance load), noise
on, so the feedback meets the sensor noise it must not amplify. The policy's k input stays spring.json's in
every row: like the robot, it is not told the true stiffness, and learns a command that serves the range.
Each epoch: one pass without gradients over whole trials records the state at each window start and
scores the validation trials (mean |Hall error|, rad); then BPTT through the truncated windows of
`window_steps` samples (all, or `windows_per_epoch` of them, in a seeded random order), each from its
recorded start, one Adam step per window on

    loss = mean (target - hall)^2 [rad^2] + `rate_weight_s2` * mean (d(command - target)/dt)^2 [(rad/s)^2]

over the training rows (the target's own rate is prescribed; only the correction's rate is penalised:
1e-5 s^2 prices a 0.02 rad chatter at 50 Hz, about 16 (rad/s)^2, like a 0.013 rad tracking error, and a
gait correction's 1-2 (rad/s)^2 at a tenth of the hanging knee's squared error).
Stop rule: the validation error has not dropped by more than `min_improvement` (1 %) below its best for
`patience` (4) epochs in a row; each such epoch also multiplies Adam's step size by `lr_decay`. The
result is the best epoch's policy (epoch 0: the initial one) among epochs whose validation commands rest
without chatter (`closedloop.chatter_rms` below half the oscillation flag's threshold); `max_epochs` caps the
run, and `max_seconds` (none by default; `seadesign train` gives one) its wall time. One intra-op thread by
default: the batch is small and per-step ops dominate, so a second thread only adds synchronisation
(measured in docs/validation/timing.md).
"""

from __future__ import annotations

import copy
import math
import os
import time
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np
import torch
from torch import nn
from torch.nn.utils import parametrize

from seadesign.corrector.closedloop import CHATTER_RMS_RAD, chatter_rms
from seadesign.corrector.closedloop_policy import FEEDBACK_LIPSCHITZ_RAD_PER_RAD, ClosedLoopPolicy, measured_inputs
from seadesign.corrector.early_stopping import KeepBest
from seadesign.corrector.imitation import TRAIN_K_SCALES, TRAIN_SPEEDS
from seadesign.corrector.models import CorrectorNet
from seadesign.corrector.reference import ReferenceWindow, reference_features
from seadesign.errors import SeadesignError
from seadesign.twin import Trial
from seadesign.twin.config import KneeConfig, knee_effects
from seadesign.twin.torch_knee import Policy, TorchKnee, TorchObservation, protocol_tensors, rollout
from seadesign.twin.walk import DIRECTIONS, Gait

#: validation walk speeds (m/s): neither the protocol's nor the training's
VAL_SPEEDS = (0.125,)


@dataclass(frozen=True)
class ClosedLoopSettings:
    """Trials (speeds m/s, trial_s s, rate_hz Hz), BPTT (window_steps samples), loss weight rate_weight_s2 (s^2),
    Adam (lr 1/step), stop rule (min_improvement relative, patience epochs), caps (max_epochs, max_seconds s)."""

    window: ReferenceWindow = ReferenceWindow()
    speeds: tuple[float, ...] = TRAIN_SPEEDS
    val_speeds: tuple[float, ...] = VAL_SPEEDS
    directions: tuple[str, ...] = tuple(DIRECTIONS)
    conditions: tuple[str, ...] = ("hanging", "ground")  # the leg hanging, the foot on the ground
    k_scales: tuple[float, ...] = TRAIN_K_SCALES
    trial_s: float = 10.0
    rate_hz: float = 100.0
    gait: Gait = Gait()
    window_steps: int = 100
    windows_per_epoch: int = 0
    rate_weight_s2: float = 1e-5
    lr: float = 1e-2
    lr_decay: float = 0.5
    grad_clip: float = 1.0
    min_improvement: float = 0.01
    patience: int = 4
    max_epochs: int = 60
    max_seconds: float = math.inf  # none: the run ends on its epochs and patience (the CLI caps it)
    hidden: int = 32
    layers: int = 2
    lipschitz_rad_per_rad: float = FEEDBACK_LIPSCHITZ_RAD_PER_RAD
    noise: bool = True
    seed: int = 0
    threads: int = 1

    def __post_init__(self) -> None:
        if not set(self.conditions) <= {"hanging", "ground"} or not self.conditions:
            raise SeadesignError(f"conditions must be hanging and/or ground, got {self.conditions}")
        if self.window_steps < 2 or self.windows_per_epoch < 0 or self.patience < 1 or self.max_epochs < 1:
            raise SeadesignError("window_steps must be >= 2, windows_per_epoch >= 0 (0: all), patience and "
                                 "max_epochs >= 1")
        if self.rate_weight_s2 < 0 or self.lr <= 0 or self.min_improvement < 0 or not 0 < self.lr_decay <= 1:
            raise SeadesignError("rate_weight_s2 and min_improvement must be >= 0, lr > 0, lr_decay in (0, 1]")
        if not self.k_scales or min(self.k_scales) <= 0:
            raise SeadesignError(f"k_scales must be non-empty and > 0, got {self.k_scales}")
        if not self.speeds or not self.val_speeds or set(self.speeds) & set(self.val_speeds):
            raise SeadesignError(f"training speeds {self.speeds} and validation speeds {self.val_speeds} must be "
                                 "non-empty and disjoint")

    def trials(self, speeds: tuple[float, ...]) -> list[Trial]:
        return [Trial(d, s, self.trial_s) for d in self.directions for s in speeds]

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


#: settings for fine-tuning a reference-network network (the default corrector): Adam's step a tenth of the from-scratch
#: one, as the feed-forward starts trained
FINE_TUNING = ClosedLoopSettings(lr=1e-3)


@dataclass
class ClosedLoopResult:
    """The trained policy and its record. curve rows: epoch, validation mean |Hall error| (rad), validation rest
    chatter (rad, max over trials), mean training loss of the epoch's windows, time in BPTT (s), elapsed (s);
    simulated_steps: samples of the whole batch simulated (no-gradient passes and windows), trained_steps:
    those inside BPTT windows."""

    policy: ClosedLoopPolicy
    settings: ClosedLoopSettings
    curve: list[dict] = field(default_factory=list)
    best_epoch: int = 0
    stopped: str = ""
    wall_s: float = 0.0
    simulated_steps: int = 0
    trained_steps: int = 0

    def summary(self) -> dict[str, Any]:
        best = self.curve[self.best_epoch] if self.curve else {}
        return {"settings": self.settings.to_dict(), "best_epoch": self.best_epoch, "epochs_run": len(self.curve),
                "stopped": self.stopped, "wall_s": round(self.wall_s, 2), "simulated_steps": self.simulated_steps,
                "trained_steps": self.trained_steps, "best_val_mean_abs_error_rad": best.get("val_mean_abs_error_rad"),
                "feedback_lipschitz_bound_rad_per_rad": self.policy.feedback_lipschitz_bound()}


@dataclass
class _Batch:
    """Training and validation trials in one torch knee: targets, stances (trials, steps, 2), reference features
    (trials, steps, 2, d) and which rows train."""

    knee: TorchKnee
    target: torch.Tensor
    stance: torch.Tensor
    features: torch.Tensor
    train_rows: torch.Tensor
    val_rows: torch.Tensor


def _batch(spring: dict, settings: ClosedLoopSettings) -> _Batch:
    """Rows: for each setting and k scale, the training then the validation trials. The knee's stiffness is
    scaled per row; the policy's k input stays spring.json's (the corrector is not told the robot's k)."""
    train, val = settings.trials(settings.speeds), settings.trials(settings.val_speeds)
    _, target, stance = protocol_tensors(train + val, settings.rate_hz, settings.gait)
    n, groups = len(train) + len(val), [(st, scale) for st in settings.conditions for scale in settings.k_scales]
    target = target.repeat(len(groups), 1, 1)
    ground = torch.tensor([float(st == "ground") for st, _ in groups]).repeat_interleave(n)
    scale = torch.tensor([scale for _, scale in groups], dtype=torch.float64).repeat_interleave(n)
    stance = stance.repeat(len(groups), 1, 1) * ground[:, None, None]
    k = float(spring["k_Nm_per_rad"])
    feats = reference_features(np.moveaxis(target.numpy(), 2, 1), np.moveaxis(stance.numpy(), 2, 1), k, settings.window)
    rows = torch.arange(len(target))
    is_val = (rows % n) >= len(train)
    config = KneeConfig.from_spring(spring)
    knee = TorchKnee(config, knee_effects(config, ground=True).configure("stiffness_scale", enabled=True),
                     rate_hz=settings.rate_hz, noise=settings.noise, seed=settings.seed)
    knee.vary("stiffness_scale", scale=scale[:, None])
    return _Batch(knee, target, stance, torch.as_tensor(np.moveaxis(feats, 1, 2), dtype=torch.float32),
                  rows[~is_val], rows[is_val])


def window_policy(policy: ClosedLoopPolicy, features: torch.Tensor, target_rad: torch.Tensor, k0: int,
                  n_steps: int, dt_s: float) -> Policy:
    """The policy as a `torch_knee.rollout` policy over samples k0 ... k0 + n_steps - 1 of trajectories with
    reference features (trials, steps, 2, d) and flexion targets (trials, steps, 2) rad; the feed-forward and the
    feedback's reference context are evaluated for the whole window at once. Commands in the targets' dtype."""
    dtype = policy.ff.x_mean.dtype
    x = features[:, k0: k0 + n_steps].to(dtype)
    ff = policy.ff(x)
    ctx = policy.feedback.context(policy.ff.normalise(x))
    h0 = policy.feedback.from_context(torch.zeros(*x.shape[:-1], 2, dtype=dtype), ctx)
    scale, out = policy.lipschitz_rad_per_rad, target_rad.dtype

    def act(obs: TorchObservation, k: int) -> torch.Tensor:
        j = k - k0
        m = measured_inputs(target_rad[:, k], target_rad[:, max(k - 1, 0)], obs.hall_rad,
                            obs.hall_velocity_rad_per_s, dt_s)
        fb = policy.feedback.from_context(m.to(dtype), ctx[:, j]).to(out) - h0[:, j].to(out)
        return ff[:, j].to(out) + scale * fb

    return act


def _window_loss(out: dict[str, torch.Tensor], target: torch.Tensor, rows: torch.Tensor, dt: float,
                 rate_weight_s2: float) -> torch.Tensor:
    err = (target - out["hall_rad"])[rows]
    corr = (out["command_rad"] - target)[rows]
    rate = torch.diff(corr, dim=1) / dt
    return (err ** 2).mean() + rate_weight_s2 * (rate ** 2).mean()


def _record(policy: ClosedLoopPolicy, b: _Batch, window_steps: int) -> tuple[list[dict], dict[str, np.ndarray]]:
    """Whole trials without gradients: the state at each window start, and the logged hall and command."""
    n = b.target.shape[1]
    b.knee.reset(b.target[:, 0], b.stance[:, 0])
    starts, hall, cmd = [], [], []
    with torch.no_grad(), parametrize.cached():
        for k0 in range(0, n, window_steps):
            starts.append(b.knee.state())
            w = min(window_steps, n - k0)
            out = rollout(b.knee, window_policy(policy, b.features, b.target, k0, w, b.knee.dt), b.stance, w)
            hall.append(out["hall_rad"])
            cmd.append(out["command_rad"])
    return starts, {"hall": torch.cat(hall, 1).numpy(), "command": torch.cat(cmd, 1).numpy()}


def train_closed_loop(spring: dict, settings: ClosedLoopSettings = ClosedLoopSettings(),
                      init: CorrectorNet | None = None) -> ClosedLoopResult:
    """Train a closed-loop policy through the torch knee; `init` a reference network to fine-tune (None: scratch)."""
    threads_before = torch.get_num_threads()
    torch.set_num_threads(settings.threads or min(2, os.cpu_count() or 1))
    try:
        return _train(spring, settings, init)
    finally:
        torch.set_num_threads(threads_before)


def _train(spring: dict, settings: ClosedLoopSettings, init: CorrectorNet | None) -> ClosedLoopResult:
    t0 = time.perf_counter()
    batch = _batch(spring, settings)
    opts = {"hidden": settings.hidden, "layers": settings.layers,
            "lipschitz_rad_per_rad": settings.lipschitz_rad_per_rad}
    if init is None:
        training_features = batch.features[batch.train_rows].reshape(-1, batch.features.shape[-1]).numpy()
        policy = ClosedLoopPolicy.from_scratch(training_features, settings.window, settings.seed, **opts)
    else:
        policy = ClosedLoopPolicy.from_feedforward(init, settings.window, settings.seed, **opts)
    opt = torch.optim.Adam(policy.parameters(), lr=settings.lr)
    gen = torch.Generator().manual_seed(settings.seed)
    n_steps = batch.target.shape[1]
    n_windows = -(-n_steps // settings.window_steps)
    target_val = batch.target[batch.val_rows].numpy()
    curve: list[dict] = []
    stop, best_state, stopped = KeepBest(settings.patience, settings.min_improvement), None, "max_epochs"
    simulated = trained = 0
    for epoch in range(settings.max_epochs + 1):
        policy.eval()
        starts, log = _record(policy, batch, settings.window_steps)
        simulated += n_steps
        val_err = float(np.mean(np.abs(target_val - log["hall"][batch.val_rows.numpy()])))
        chatter = float(np.nanmax(chatter_rms(log["command"][batch.val_rows.numpy()], target_val, settings.rate_hz)))
        calm = chatter < 0.5 * CHATTER_RMS_RAD
        row = {"epoch": epoch, "val_mean_abs_error_rad": val_err, "val_rest_chatter_rad": chatter,
               "train_loss": float("nan"), "bptt_s": 0.0, "elapsed_s": time.perf_counter() - t0}
        curve.append(row)
        if stop.update(epoch, val_err, admissible=calm):
            best_state = copy.deepcopy(policy.state_dict())
        if not stop.improved:
            for group in opt.param_groups:
                group["lr"] *= settings.lr_decay
        if stop.exhausted:
            stopped = "patience"
            break
        if epoch == settings.max_epochs:
            break
        if time.perf_counter() - t0 > settings.max_seconds:
            stopped = "time_limit"
            break
        policy.train()
        losses, t_bptt = [], time.perf_counter()
        for w in torch.randperm(n_windows, generator=gen)[: settings.windows_per_epoch or n_windows].tolist():
            k0 = w * settings.window_steps
            steps = min(settings.window_steps, n_steps - k0)
            batch.knee.load_state(starts[w])
            opt.zero_grad(set_to_none=True)
            with parametrize.cached():
                window = window_policy(policy, batch.features, batch.target, k0, steps, batch.knee.dt)
                out = rollout(batch.knee, window, batch.stance, steps)
                loss = _window_loss(out, batch.target[:, k0: k0 + steps], batch.train_rows, batch.knee.dt,
                                    settings.rate_weight_s2)
                loss.backward()
            nn.utils.clip_grad_norm_(policy.parameters(), settings.grad_clip)
            opt.step()
            losses.append(loss.item())
            simulated += steps
            trained += steps
        row["train_loss"] = float(np.mean(losses))
        row["bptt_s"] = time.perf_counter() - t_bptt
    if best_state is None:
        raise SeadesignError("no epoch of closed-loop training rested without chatter on the validation trials; "
                             "lower lipschitz_rad_per_rad or raise rate_weight_s2")
    policy.load_state_dict(best_state)
    policy.eval()
    return ClosedLoopResult(policy, settings, curve, stop.best_epoch, stopped, time.perf_counter() - t0, simulated,
                            trained)
