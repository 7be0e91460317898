"""The closed-loop policy: its network, its certified feedback bound and its export (trained by
`closedloop_training` through the closed loop, in the differentiable knee `twin.torch_knee`).

The policy, per knee and control step, in flexion (the right knee mirrored in and out):

    command = ff(x) + L [h(m, x) - h(0, x)]

- x: the reference window (`reference.reference_features`, the reference network's inputs), so a reference network
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
"""

from __future__ import annotations

import copy
from typing import Any

import numpy as np
import torch
from torch import nn
from torch.nn.utils import parametrize

from seadesign.corrector.export import NumpyClosedLoop
from seadesign.corrector.models import CorrectorNet, MLPCore
from seadesign.corrector.reference import ReferenceWindow
from seadesign.corrector.runtime import ClosedLoopCorrector
from seadesign.errors import SeadesignError

#: bound on the feedback's Lipschitz constant w.r.t. m (rad/rad); see the module docstring
FEEDBACK_LIPSCHITZ_RAD_PER_RAD = 0.5
#: time scale of the error-rate input (s): m = (e, RATE_TIME_S de/dt)
RATE_TIME_S = 0.01
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
