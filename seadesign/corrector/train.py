"""Training: seeded, early stopping on the validation set, data kept in tensors, large batches.

Loss on the standardised command (MSE); Siamese adds lambda * MSE of the standardised x_t+1
(thesis eq. 5.5, lambda = 0.1). Adam instead of the thesis's lr 1e-6 / batch 32, which would
not converge within a minute on a CPU; the settings used are stored with every model.
"""

from __future__ import annotations

import math
import os
import time
from dataclasses import asdict, dataclass, field

import numpy as np
import torch
from torch import nn

from seadesign.corrector.dataset import CorrectorDataset
from seadesign.corrector.early_stopping import KeepBest
from seadesign.corrector.models import CorrectorNet, SiameseCore, base_weights, make_core
from seadesign.corrector.splits import Split
from seadesign.errors import SeadesignError


@dataclass(frozen=True)
class TrainConfig:
    """Training settings. lr in 1/step (Adam); max_seconds is a wall-clock cap in s, none by default, so that a
    run ends on its epochs and patience and trains the same on every machine (the CLI caps it)."""

    model: str = "mlp"
    hidden: int = 64
    layers: int = 3
    lr: float = 3e-3
    batch_size: int = 512
    max_epochs: int = 400
    patience: int = 40
    lambda_x: float = 0.1
    weight_decay: float = 0.0
    seed: int = 0
    max_seconds: float = math.inf
    threads: int = 0  # 0: min(2, cpu count)
    device: str = "auto"


@dataclass
class TrainResult:
    """A trained corrector and how it got there. curve rows: epoch, train loss (standardised), val MSE (rad^2), s."""

    net: CorrectorNet
    config: TrainConfig
    curve: list[dict] = field(default_factory=list)
    best_epoch: int = 0
    stopped: str = ""
    wall_s: float = 0.0
    samples_per_s: float = 0.0
    device: str = "cpu"

    def summary(self) -> dict:
        """JSON-ready settings and outcome."""
        best = self.curve[self.best_epoch] if self.curve else {}
        return {"config": asdict(self.config), "best_epoch": self.best_epoch, "epochs_run": len(self.curve),
                "stopped": self.stopped, "wall_s": round(self.wall_s, 3),
                "samples_per_s": round(self.samples_per_s, 1), "device": self.device,
                "best_val_mse_rad2": best.get("val_mse_rad2")}


def _device(name: str) -> torch.device:
    if name == "auto":
        return torch.device("cuda" if torch.cuda.is_available() else "cpu")
    return torch.device(name)


def _inputs(ds: CorrectorDataset, siamese: bool) -> np.ndarray:
    return np.concatenate([ds.X, ds.X_next], axis=1) if siamese else ds.X


def fit(ds: CorrectorDataset, split: Split, k_Nm_per_rad: float, config: TrainConfig = TrainConfig()) -> TrainResult:
    """Train `config.model` on split.train, early-stop on split.val; returns the best-validation network."""
    if config.model == "history" and ds.spec.history == 0:
        raise SeadesignError("model 'history' needs a history window; pass --history N (samples, e.g. 3)")
    siamese = config.model == "siamese"
    w = base_weights(config.model, ds.feature_names, k_Nm_per_rad)
    return fit_arrays(_inputs(ds, siamese), ds.y, split, w, config, d_state=ds.X.shape[1])


def fit_arrays(X: np.ndarray, y: np.ndarray, split: Split, base_w: torch.Tensor, config: TrainConfig,
               d_state: int | None = None) -> TrainResult:
    """Train a `CorrectorNet` with fixed base weights `base_w` on raw inputs X (N, d) and commands y (N,) rad;
    rows split.train to fit, split.val to stop early. `d_state`: length of one state vector (Siamese)."""
    if len(split.train) == 0 or len(split.val) == 0:
        raise SeadesignError(f"split '{split.name}' left an empty training or validation set; give more data")
    threads_before = torch.get_num_threads()
    torch.set_num_threads(config.threads or min(2, os.cpu_count() or 1))
    try:
        return _fit(X, y, split, base_w, config, d_state or X.shape[1])
    finally:
        torch.set_num_threads(threads_before)


def _fit(X_np: np.ndarray, y_np: np.ndarray, split: Split, w: torch.Tensor, cfg: TrainConfig, d_state: int) -> TrainResult:
    siamese = cfg.model == "siamese"
    dev = _device(cfg.device)
    torch.manual_seed(cfg.seed)
    gen = torch.Generator().manual_seed(cfg.seed)

    X = torch.as_tensor(X_np, dtype=torch.float32)
    y = torch.as_tensor(y_np, dtype=torch.float32)
    tr, va = torch.as_tensor(split.train), torch.as_tensor(split.val)
    x_mean, x_std = X[tr].mean(0), X[tr].std(0)
    x_std = torch.where(x_std > 1e-8, x_std, torch.ones_like(x_std))
    if siamese:  # one normalisation for x_t and x_t+1: the encoder is shared
        both = torch.cat([X[tr, :d_state], X[tr, d_state:]])
        m, s = both.mean(0), both.std(0)
        s = torch.where(s > 1e-8, s, torch.ones_like(s))
        x_mean, x_std = torch.cat([m, m]), torch.cat([s, s])
    resid = y - X @ w
    y_mean, y_std = float(resid[tr].mean()), float(resid[tr].std().clamp_min(1e-8))
    net = CorrectorNet(make_core(cfg.model, d_state, cfg.hidden, cfg.layers), x_mean, x_std, y_mean, y_std, w)
    net.to(dev)

    Xn = ((X - x_mean) / x_std).to(dev)
    yn = ((resid - y_mean) / y_std).to(dev)
    X, y = X.to(dev), y.to(dev)
    opt = torch.optim.Adam(net.parameters(), lr=cfg.lr, weight_decay=cfg.weight_decay)
    mse = nn.MSELoss()

    def loss_on(idx: torch.Tensor) -> torch.Tensor:
        xb, ub = Xn[idx], net.core(Xn[idx])
        loss = mse(ub, yn[idx])
        if siamese:
            core: SiameseCore = net.core  # type: ignore[assignment]
            d_s = core.d_state
            u_n = (y[idx] - X[idx] @ net.base_w - net.y_mean) / net.y_std  # true command, standardised
            loss = loss + cfg.lambda_x * mse(core.predict_next(xb[:, :d_s], u_n), xb[:, d_s:])
        return loss

    curve: list[dict] = []
    stop, best_state, stopped = KeepBest(cfg.patience), None, "max_epochs"
    t0, seen = time.perf_counter(), 0
    for epoch in range(cfg.max_epochs):
        net.train()
        perm = tr[torch.randperm(len(tr), generator=gen)].to(dev)
        total = 0.0
        for i in range(0, len(perm), cfg.batch_size):
            idx = perm[i: i + cfg.batch_size]
            opt.zero_grad(set_to_none=True)
            loss = loss_on(idx)
            loss.backward()
            opt.step()
            total += loss.item() * len(idx)
        seen += len(perm)
        net.eval()
        with torch.no_grad():
            val = float(((net(X[va.to(dev)]) - y[va.to(dev)]) ** 2).mean())
        curve.append({"epoch": epoch, "train_loss_std": total / len(perm), "val_mse_rad2": val,
                      "elapsed_s": time.perf_counter() - t0})
        if stop.update(epoch, val):
            best_state = {k_: v.detach().clone() for k_, v in net.state_dict().items()}
        if stop.exhausted:
            stopped = "patience"
            break
        if time.perf_counter() - t0 > cfg.max_seconds:
            stopped = "time_limit"
            break
    wall = time.perf_counter() - t0
    if best_state is not None:
        net.load_state_dict(best_state)
    net.cpu().eval()
    return TrainResult(net, cfg, curve, stop.best_epoch, stopped, wall, seen / wall if wall > 0 else 0.0, str(dev))
