"""Corrector networks. Every learned corrector is a `CorrectorNet`: raw SI inputs in, motor command (rad) out.

    u = base_w . x  +  y_mean + y_std * core((x - x_mean) / x_std)

`base_w` is the part the network does not have to learn: zero for the thesis's networks, and
target + effort / k for the physics-residual network, whose core learns only what that
feed-forward misses. The normalisation is part of the module, so the export carries it.

Cores: `MLPCore` (thesis: 3 x 64, leaky ReLU; also used with a history window) and
`SiameseCore` (thesis sec. 5.3.2: shared 3 x 64 encoder for x_t and x_t+1, a head for u_t from
both latents and a head for x_t+1 from the x_t latent and u_t; ReLU as in the thesis).
"""

from __future__ import annotations

import torch
from torch import nn

from seadesign.errors import SeadesignError

MODEL_KINDS = ("mlp", "siamese", "history", "residual")


def _stack(d_in: int, hidden: int, layers: int, act: type[nn.Module]) -> nn.Sequential:
    mods: list[nn.Module] = []
    for i in range(layers):
        mods += [nn.Linear(d_in if i == 0 else hidden, hidden), act()]
    return nn.Sequential(*mods)


class MLPCore(nn.Module):
    """Multi-layer perceptron: `layers` x `hidden` leaky ReLU, one linear output. (B, d) -> (B,)."""

    def __init__(self, d_in: int, hidden: int = 64, layers: int = 3) -> None:
        super().__init__()
        self.body = _stack(d_in, hidden, layers, nn.LeakyReLU)
        self.out = nn.Linear(hidden, 1)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return self.out(self.body(x)).squeeze(-1)


class SiameseCore(nn.Module):
    """Siamese network on x = [x_t, x_t+1] (B, 2 d_state) -> u_t (B,); `predict_next` gives x_t+1."""

    def __init__(self, d_state: int, hidden: int = 64, layers: int = 3) -> None:
        super().__init__()
        self.d_state = d_state
        self.encoder = _stack(d_state, hidden, layers, nn.ReLU)
        self.u_head = nn.Linear(2 * hidden, 1)
        self.x_head = nn.Linear(hidden + 1, d_state)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        z_t = self.encoder(x[:, : self.d_state])
        z_next = self.encoder(x[:, self.d_state:])
        return self.u_head(torch.cat([z_t, z_next], dim=1)).squeeze(-1)

    def predict_next(self, x_t: torch.Tensor, u: torch.Tensor) -> torch.Tensor:
        """Forward model: normalised x_t and u_t -> normalised x_t+1."""
        return self.x_head(torch.cat([self.encoder(x_t), u.unsqueeze(-1)], dim=1))


class CorrectorNet(nn.Module):
    """Normalisation + base term + core. forward: raw inputs (B, d_in) in SI -> command (B,) rad."""

    def __init__(self, core: nn.Module, x_mean: torch.Tensor, x_std: torch.Tensor, y_mean: float, y_std: float,
                 base_w: torch.Tensor) -> None:
        super().__init__()
        self.core = core
        self.register_buffer("x_mean", x_mean.float())
        self.register_buffer("x_std", x_std.float())
        self.register_buffer("y_mean", torch.tensor(float(y_mean)))
        self.register_buffer("y_std", torch.tensor(float(y_std)))
        self.register_buffer("base_w", base_w.float())

    def normalise(self, x: torch.Tensor) -> torch.Tensor:
        """Raw inputs -> the core's standardised inputs."""
        return (x - self.x_mean) / self.x_std

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return x @ self.base_w + self.y_mean + self.y_std * self.core(self.normalise(x))


def make_core(kind: str, d_state: int, hidden: int = 64, layers: int = 3) -> nn.Module:
    """The core for a model kind; `d_state` is the length of one input vector x_t."""
    if kind == "siamese":
        return SiameseCore(d_state, hidden, layers)
    if kind in MODEL_KINDS:
        return MLPCore(d_state, hidden, layers)
    raise SeadesignError(f"unknown model '{kind}' (--model); choose one of {', '.join(MODEL_KINDS)}")


def base_weights(kind: str, feature_names: tuple[str, ...], k_Nm_per_rad: float) -> torch.Tensor:
    """Weights of the fixed base term over the raw inputs (Siamese: over [x_t, x_t+1])."""
    names = feature_names * 2 if kind == "siamese" else feature_names
    w = torch.zeros(len(names))
    if kind == "residual":
        if "effort_Nm" not in feature_names:
            raise SeadesignError(
                "the physics-residual model needs the effort input; add 'effort' to --modalities "
                "(e.g. --modalities velocity_effort)"
            )
        w[names.index("target_rad")] = 1.0
        w[names.index("effort_Nm")] = 1.0 / k_Nm_per_rad
    return w
