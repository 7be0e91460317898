"""The closed-loop policy: a corrector trained through the closed loop, in the differentiable knee (`twin.torch_knee`).

The policy, per knee and control step, in flexion (the right knee mirrored in and out):

    command = ff(x) + L [h(m, x) - h(0, x)]

- x: the reference window (`reference.reference_features`, the reference-network inputs), so a reference-network network
  can be `ff` and be fine-tuned; from scratch `ff` starts as command = target;
- m = (e, tau de/dt) (rad): the Hall error e = target - hall and its rate (target's finite difference
  minus the measured Hall velocity) times tau = `RATE_TIME_S` (one 100 Hz sample), so both are in rad;
- h: a small tanh network whose m-weights and all later layers are divided by max(1, their exact
  largest singular value), so ||dh/dm|| <= 1 and the feedback's Lipschitz constant w.r.t. the
  measured inputs is at most L = `FEEDBACK_LIPSCHITZ_RAD_PER_RAD` (rad/rad, 2-norm over m), for every
  reference window x (x may schedule the gain, never raise it). Zero error gives zero feedback. The exact
  norm (an SVD of matrices of at most 32 x 33, once per window) rather than torch's power-iteration
  `spectral_norm`, whose estimate may lie below the norm and so let a layer's gain pass 1.

Why L = 0.5: the servo-spring-link loop closed through the Hall sensor with one sample of delay
oscillates at a proportional gain of about 1 (measured in the knee simulator on the thesis's
trials: kp 1.0 flagged as oscillating at rest, hanging and ground; kp 0.5 rests with 0.005-0.008 rad
chatter against the 0.02 rad threshold). L = 0.5 keeps a gain margin of 2 against that, and the linear
feedbacks a e + b tau de/dt with a^2 + b^2 = L^2 (8 points on the bound's circle, two trials of 3 s, hanging
and ground) ran unflagged there. That check covers fixed linear gains; a gain scheduled by x within the
bound is not covered by a theorem here, which is why training also keeps only epochs that rest calmly.

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
from seadesign.corrector.early_stopping import KeepBest
from seadesign.corrector.export import NumpyClosedLoop
from seadesign.corrector.imitation import TRAIN_K_SCALES, TRAIN_SPEEDS
from seadesign.corrector.models import CorrectorNet, MLPCore
from seadesign.corrector.reference import ReferenceWindow, reference_features
from seadesign.corrector.runtime import ClosedLoopCorrector
from seadesign.errors import SeadesignError
from seadesign.twin import Trial
from seadesign.twin.config import KneeConfig, knee_effects
from seadesign.twin.torch_knee import Policy, TorchKnee, TorchObservation, protocol_tensors, rollout
from seadesign.twin.walk import DIRECTIONS, Gait

#: bound on the feedback's Lipschitz constant w.r.t. m (rad/rad); see the module docstring
FEEDBACK_LIPSCHITZ_RAD_PER_RAD = 0.5
#: time scale of the error-rate input (s): m = (e, RATE_TIME_S de/dt)
RATE_TIME_S = 0.01
#: validation walk speeds (m/s): neither the protocol's nor the training's
VAL_SPEEDS = (0.125,)
#: output scale of a feed-forward network started from scratch (rad): the size of a correction
SCRATCH_OUTPUT_RAD = 0.1


class _SpectralBound(nn.Module):
    """Weight parametrisation W -> W / max(1, ||W||_2), with the exact largest singular value: ||W||_2 <= 1."""

    def forward(self, w: torch.Tensor) -> torch.Tensor:
        return w / torch.linalg.matrix_norm(w, ord=2).clamp(min=1.0)


def _bounded(layer: nn.Linear) -> nn.Linear:
    parametrize.register_parametrization(layer, "weight", _SpectralBound())
    return layer


class FeedbackBranch(nn.Module):
    """h(m, xn): tanh layers; m (..., 2) rad enters through a bounded matrix, the standardised reference window
    xn (..., d) through a free one (with the bias); the hidden and output layers are bounded, so ||dh/dm|| <= 1."""

    def __init__(self, d_reference: int, hidden: int = 32, layers: int = 2) -> None:
        super().__init__()
        if layers < 1 or hidden < 1:
            raise SeadesignError(f"feedback branch needs >= 1 layer of >= 1 unit, got {layers} x {hidden}")
        self.m_in = _bounded(nn.Linear(2, hidden, bias=False))
        self.x_in = nn.Linear(d_reference, hidden)
        self.hidden = nn.ModuleList(_bounded(nn.Linear(hidden, hidden)) for _ in range(layers - 1))
        self.out = nn.Linear(hidden, 1)
        with torch.no_grad():
            self.out.weight.mul_(0.01)  # start close to no feedback
        _bounded(self.out)

    def context(self, xn: torch.Tensor) -> torch.Tensor:
        """The reference window's part of the first layer (..., hidden); computed once per window."""
        return self.x_in(xn)

    def from_context(self, m: torch.Tensor, context: torch.Tensor) -> torch.Tensor:
        """h (...,) from m (..., 2) rad and `context`."""
        z = torch.tanh(self.m_in(m) + context)
        for layer in self.hidden:
            z = torch.tanh(layer(z))
        return self.out(z).squeeze(-1)

    def lipschitz_factor(self) -> float:
        """Product of the bounded layers' exact spectral norms (<= 1): ||dh/dm|| is at most this."""
        out = 1.0
        for layer in (self.m_in, *self.hidden, self.out):
            out *= float(torch.linalg.matrix_norm(layer.weight.detach(), ord=2))
        return out


class ClosedLoopPolicy(nn.Module):
    """command = ff(x) + L [h(m, x) - h(0, x)] (rad, flexion); `ff` a `CorrectorNet` on the reference window."""

    def __init__(self, ff: CorrectorNet, window: ReferenceWindow, hidden: int = 32, layers: int = 2,
                 lipschitz_rad_per_rad: float = FEEDBACK_LIPSCHITZ_RAD_PER_RAD) -> None:
        super().__init__()
        d = len(window.feature_names())
        if not isinstance(ff.core, MLPCore):
            raise SeadesignError(f"the feed-forward part must be an MLP network, got {type(ff.core).__name__}")
        if ff.x_mean.shape[0] != d:
            raise SeadesignError(f"feed-forward network takes {ff.x_mean.shape[0]} inputs, the reference window "
                                 f"{window.to_dict()} gives {d}; use the window it was trained with")
        if not lipschitz_rad_per_rad >= 0:
            raise SeadesignError(f"feedback Lipschitz bound must be >= 0 rad/rad, got {lipschitz_rad_per_rad}")
        self.ff, self.window, self.lipschitz_rad_per_rad = ff, window, float(lipschitz_rad_per_rad)
        self.feedback = FeedbackBranch(d, hidden, layers)

    @classmethod
    def from_scratch(cls, features: np.ndarray, window: ReferenceWindow, seed: int = 0,
                     **options: Any) -> "ClosedLoopPolicy":
        """A policy whose feed-forward starts at command = target (plus a small random correction), normalised on
        `features` (N, d) (the training inputs); hidden 3 x 64 leaky ReLU as the reference network."""
        torch.manual_seed(seed)
        x = torch.as_tensor(features, dtype=torch.float32)
        x_mean, x_std = x.mean(0), x.std(0)
        x_std = torch.where(x_std > 1e-8, x_std, torch.ones_like(x_std))
        w = torch.zeros(x.shape[1])
        w[0] = 1.0  # command = target + learned correction
        core = MLPCore(x.shape[1])
        with torch.no_grad():
            core.out.weight.mul_(0.01)
            core.out.bias.zero_()
        return cls(CorrectorNet(core, x_mean, x_std, 0.0, SCRATCH_OUTPUT_RAD, w), window, **options)

    @classmethod
    def from_feedforward(cls, ff: CorrectorNet, window: ReferenceWindow, seed: int = 0,
                         **options: Any) -> "ClosedLoopPolicy":
        """Fine-tune a reference-network network (a copy; the original is left as it is)."""
        torch.manual_seed(seed)
        return cls(copy.deepcopy(ff).float(), window, **options)

    def forward(self, x: torch.Tensor, m: torch.Tensor) -> torch.Tensor:
        """Command (...,) rad from the reference window x (..., d) and the measured inputs m (..., 2) rad."""
        ctx = self.feedback.context(self.ff.normalise(x))
        fb = self.feedback.from_context(m, ctx) - self.feedback.from_context(torch.zeros_like(m), ctx)
        return self.ff(x) + self.lipschitz_rad_per_rad * fb

    def feedback_lipschitz_bound(self) -> float:
        """Certified bound on ||d command / d m|| (rad/rad): L times the bounded layers' spectral norms (<= L)."""
        return self.lipschitz_rad_per_rad * self.feedback.lipschitz_factor()


def measured_inputs(target_rad: torch.Tensor, prev_target_rad: torch.Tensor, hall_rad: torch.Tensor,
                    hall_velocity_rad_per_s: torch.Tensor, dt_s: float) -> torch.Tensor:
    """m = (e, RATE_TIME_S (target rate - Hall velocity)) (..., 2) in rad, flexion."""
    rate = (target_rad - prev_target_rad) / dt_s - hall_velocity_rad_per_s
    return torch.stack([target_rad - hall_rad, RATE_TIME_S * rate], dim=-1)


# -- training ------------------------------------------------------------------------------------------------
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


def _batch(spring: dict, s: ClosedLoopSettings) -> _Batch:
    """Rows: for each setting and k scale, the training then the validation trials. The knee's stiffness is
    scaled per row; the policy's k input stays spring.json's (the corrector is not told the robot's k)."""
    train, val = s.trials(s.speeds), s.trials(s.val_speeds)
    _, target, stance = protocol_tensors(train + val, s.rate_hz, s.gait)
    n, groups = len(train) + len(val), [(st, scale) for st in s.conditions for scale in s.k_scales]
    target = target.repeat(len(groups), 1, 1)
    ground = torch.tensor([float(st == "ground") for st, _ in groups]).repeat_interleave(n)
    scale = torch.tensor([scale for _, scale in groups], dtype=torch.float64).repeat_interleave(n)
    stance = stance.repeat(len(groups), 1, 1) * ground[:, None, None]
    k = float(spring["k_Nm_per_rad"])
    feats = reference_features(np.moveaxis(target.numpy(), 2, 1), np.moveaxis(stance.numpy(), 2, 1), k, s.window)
    rows = torch.arange(len(target))
    is_val = (rows % n) >= len(train)
    config = KneeConfig.from_spring(spring)
    knee = TorchKnee(config, knee_effects(config, ground=True).configure("stiffness_scale", enabled=True),
                     rate_hz=s.rate_hz, noise=s.noise, seed=s.seed)
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


def _train(spring: dict, s: ClosedLoopSettings, init: CorrectorNet | None) -> ClosedLoopResult:
    t0 = time.perf_counter()
    b = _batch(spring, s)
    opts = {"hidden": s.hidden, "layers": s.layers, "lipschitz_rad_per_rad": s.lipschitz_rad_per_rad}
    if init is None:
        policy = ClosedLoopPolicy.from_scratch(b.features[b.train_rows].reshape(-1, b.features.shape[-1]).numpy(),
                                               s.window, s.seed, **opts)
    else:
        policy = ClosedLoopPolicy.from_feedforward(init, s.window, s.seed, **opts)
    opt = torch.optim.Adam(policy.parameters(), lr=s.lr)
    gen = torch.Generator().manual_seed(s.seed)
    n_steps = b.target.shape[1]
    n_windows = -(-n_steps // s.window_steps)
    target_val = b.target[b.val_rows].numpy()
    curve: list[dict] = []
    stop, best_state, stopped = KeepBest(s.patience, s.min_improvement), None, "max_epochs"
    simulated = trained = 0
    for epoch in range(s.max_epochs + 1):
        policy.eval()
        starts, log = _record(policy, b, s.window_steps)
        simulated += n_steps
        val_err = float(np.mean(np.abs(target_val - log["hall"][b.val_rows.numpy()])))
        chatter = float(np.nanmax(chatter_rms(log["command"][b.val_rows.numpy()], target_val, s.rate_hz)))
        calm = chatter < 0.5 * CHATTER_RMS_RAD
        row = {"epoch": epoch, "val_mean_abs_error_rad": val_err, "val_rest_chatter_rad": chatter,
               "train_loss": float("nan"), "bptt_s": 0.0, "elapsed_s": time.perf_counter() - t0}
        curve.append(row)
        if stop.update(epoch, val_err, admissible=calm):
            best_state = copy.deepcopy(policy.state_dict())
        if not stop.improved:
            for group in opt.param_groups:
                group["lr"] *= s.lr_decay
        if stop.exhausted:
            stopped = "patience"
            break
        if epoch == s.max_epochs:
            break
        if time.perf_counter() - t0 > s.max_seconds:
            stopped = "time_limit"
            break
        policy.train()
        losses, t_bptt = [], time.perf_counter()
        for w in torch.randperm(n_windows, generator=gen)[: s.windows_per_epoch or n_windows].tolist():
            k0 = w * s.window_steps
            steps = min(s.window_steps, n_steps - k0)
            b.knee.load_state(starts[w])
            opt.zero_grad(set_to_none=True)
            with parametrize.cached():
                out = rollout(b.knee, window_policy(policy, b.features, b.target, k0, steps, b.knee.dt), b.stance,
                              steps)
                loss = _window_loss(out, b.target[:, k0: k0 + steps], b.train_rows, b.knee.dt, s.rate_weight_s2)
                loss.backward()
            nn.utils.clip_grad_norm_(policy.parameters(), s.grad_clip)
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
    return ClosedLoopResult(policy, s, curve, stop.best_epoch, stopped, time.perf_counter() - t0, simulated, trained)


# -- export --------------------------------------------------------------------------------------------------
#: names of the measured inputs m after the reference window in an exported policy's flat input (rad)
MEASURED_INPUTS = ("hall_error_rad", "scaled_hall_error_rate_rad")


def _plain(layer: nn.Linear) -> nn.Linear:
    """A plain linear layer with `layer`'s current (evaluated) weight and bias."""
    out = nn.Linear(layer.in_features, layer.out_features, bias=layer.bias is not None)
    with torch.no_grad():
        out.weight.copy_(layer.weight)
        if layer.bias is not None:
            out.bias.copy_(layer.bias)
    return out


class FlatPolicy(nn.Module):
    """The policy for export (TorchScript, ONNX): one raw input z = [x, m] (B, d + 2) -> command (B,) rad, flexion;
    a float32 copy whose bounded weights are evaluated once (plain linear layers and tanh; the bound holds)."""

    def __init__(self, policy: ClosedLoopPolicy) -> None:
        super().__init__()
        plain = copy.deepcopy(policy).float().eval()
        fb = plain.feedback  # new layers, not remove_parametrizations: a deep copy shares the parametrised class
        fb.m_in, fb.out = _plain(fb.m_in), _plain(fb.out)
        fb.hidden = nn.ModuleList(_plain(layer) for layer in fb.hidden)
        self.policy, self.d = plain, int(plain.ff.x_mean.shape[0])

    def forward(self, z: torch.Tensor) -> torch.Tensor:
        return self.policy(z[..., : self.d], z[..., self.d:])


def policy_arrays(policy: ClosedLoopPolicy) -> dict[str, np.ndarray]:
    """The policy as float64 arrays for `export.NumpyClosedLoop`: the input standardisation folded into the first
    layers, the feed-forward's and the feedback's first layers on the window stacked, y_std and y_mean folded into
    the feed-forward's output, L into the feedback's; `rate_time_s` (s) of the rate input."""
    arr = lambda t: t.detach().double().numpy().copy()  # noqa: E731
    ff, fb = policy.ff, policy.feedback
    lin = [m for m in ff.core.body if isinstance(m, nn.Linear)]
    inv_std, mean = 1.0 / arr(ff.x_std), arr(ff.x_mean)
    first = np.concatenate([arr(lin[0].weight), arr(fb.x_in.weight)]) * inv_std
    y_std = float(ff.y_std)
    out = {"first_W": first, "first_b": np.concatenate([arr(lin[0].bias), arr(fb.x_in.bias)]) - first @ mean,
           "n_ff": np.array(lin[0].weight.shape[0]), "n_ff_hidden": np.array(len(lin) - 1),
           "n_fb_hidden": np.array(len(fb.hidden)), "base_w": arr(ff.base_w),
           "ff_out_W": y_std * arr(ff.core.out.weight)[0],
           "ff_out_b": y_std * arr(ff.core.out.bias)[0] + float(ff.y_mean),
           "m_W": arr(fb.m_in.weight), "fb_out_W": policy.lipschitz_rad_per_rad * arr(fb.out.weight)[0],
           "rate_time_s": np.array(RATE_TIME_S)}
    for i, layer in enumerate(lin[1:]):
        out[f"ff_W{i}"], out[f"ff_b{i}"] = arr(layer.weight), arr(layer.bias)
    for i, layer in enumerate(fb.hidden):
        out[f"fb_W{i}"], out[f"fb_b{i}"] = arr(layer.weight), arr(layer.bias)
    return out


def runtime_corrector(policy: ClosedLoopPolicy, k_Nm_per_rad: float, name: str = "closedloop") -> ClosedLoopCorrector:
    """The policy as a bundle runs it (`ClosedLoopCorrector` on the NumPy path); k from spring.json."""
    return ClosedLoopCorrector(NumpyClosedLoop(policy_arrays(policy)), policy.window, k_Nm_per_rad, name)
