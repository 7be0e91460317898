"""Export a trained corrector: TorchScript (normalisation, input names and units baked in) and a
plain NumPy path with the same outputs. A bundle directory holds:

- ``corrector.pt``: TorchScript; ``forward(x)`` maps raw SI inputs (B, d) to commands (B,) rad;
  ``input_names()`` / ``input_units()`` list the inputs; ``meta.json`` is embedded as an extra file.
- ``corrector.npz``: weights and normalisation for `NumpyCorrector`.
- ``meta.json``: dataset spec, model kind, k, split, training settings and curve, versions.
"""


import json
import platform
import warnings
from pathlib import Path
from typing import Any

import numpy as np
import torch
from torch import nn

from seadesign import __version__
from seadesign.corrector.modalities import unit_of
from seadesign.corrector.models import CorrectorNet, MLPCore, SiameseCore
from seadesign.errors import SeadesignError

LEAKY_SLOPE = 0.01  # torch.nn.LeakyReLU default


class _Exported(nn.Module):
    """TorchScript wrapper carrying the input list and units."""

    names: list[str]
    units: list[str]

    def __init__(self, net: CorrectorNet, names: list[str], units: list[str]) -> None:
        super().__init__()
        self.net = net
        self.names = names
        self.units = units

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return self.net(x)

    @torch.jit.export
    def input_names(self) -> list[str]:
        return self.names

    @torch.jit.export
    def input_units(self) -> list[str]:
        return self.units


def versions() -> dict[str, str]:
    """Package versions and machine recorded with every model and result."""
    return {"seadesign": __version__, "torch": torch.__version__, "numpy": np.__version__,
            "python": platform.python_version(), "machine": f"{platform.system()} {platform.machine()}"}


def input_list(feature_names: tuple[str, ...], siamese: bool) -> list[str]:
    """Names of the flat input vector (Siamese: x_t then x_t+1)."""
    if siamese:
        return [f"{n}[t]" for n in feature_names] + [f"{n}[t+1]" for n in feature_names]
    return list(feature_names)


def _linears(seq: nn.Sequential) -> list[nn.Linear]:
    return [m for m in seq if isinstance(m, nn.Linear)]


def numpy_arrays(net: CorrectorNet) -> dict[str, np.ndarray]:
    """All weights and the normalisation as float32 NumPy arrays."""
    arr = {k: v.detach().cpu().numpy().astype(np.float32) for k, v in net.named_buffers()}
    core = net.core
    if isinstance(core, SiameseCore):
        layers, heads = _linears(core.encoder), {"u_head": core.u_head}
        arr["d_state"] = np.array(core.d_state)
    elif isinstance(core, MLPCore):
        layers, heads = _linears(core.body), {"out": core.out}
    else:
        raise SeadesignError(f"cannot export a core of type {type(core).__name__}")
    for i, lin in enumerate(layers):
        arr[f"W{i}"] = lin.weight.detach().cpu().numpy().astype(np.float32)
        arr[f"b{i}"] = lin.bias.detach().cpu().numpy().astype(np.float32)
    for name, lin in heads.items():
        arr[f"{name}_W"] = lin.weight.detach().cpu().numpy().astype(np.float32)
        arr[f"{name}_b"] = lin.bias.detach().cpu().numpy().astype(np.float32)
    arr["n_layers"] = np.array(len(layers))
    return arr


class NumpyCorrector:
    """Pure NumPy inference (float32), same outputs as the TorchScript module."""

    def __init__(self, arrays: dict[str, np.ndarray]) -> None:
        a = {k: np.asarray(v) for k, v in arrays.items()}
        self.siamese = "u_head_W" in a
        self.x_mean, self.x_std, self.base_w = a["x_mean"], a["x_std"], a["base_w"]
        self.y_mean, self.y_std = np.float32(a["y_mean"]), np.float32(a["y_std"])
        n = int(a["n_layers"])
        self.layers = [(a[f"W{i}"], a[f"b{i}"]) for i in range(n)]
        head = "u_head" if self.siamese else "out"
        self.head_W, self.head_b = a[f"{head}_W"], a[f"{head}_b"]
        self.d_state = int(a["d_state"]) if self.siamese else 0
        self.slope = np.float32(0.0 if self.siamese else LEAKY_SLOPE)

    def _body(self, z: np.ndarray) -> np.ndarray:
        for W, b in self.layers:
            z = z @ W.T + b
            z = np.maximum(z, self.slope * z)
        return z

    def __call__(self, x: np.ndarray) -> np.ndarray | float:
        """Raw SI inputs (d,) or (B, d) -> command(s), rad."""
        x = np.asarray(x, dtype=np.float32)
        single = x.ndim == 1
        xb = x[None, :] if single else x
        z = (xb - self.x_mean) / self.x_std
        if self.siamese:
            z = np.concatenate([self._body(z[:, : self.d_state]), self._body(z[:, self.d_state:])], axis=1)
        else:
            z = self._body(z)
        u = xb @ self.base_w + self.y_mean + self.y_std * (z @ self.head_W.T + self.head_b)[:, 0]
        return float(u[0]) if single else u


def export_bundle(net: CorrectorNet, meta: dict[str, Any], out_dir: str | Path) -> Path:
    """Write corrector.pt, corrector.npz and meta.json into `out_dir`."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    names = list(meta["inputs"])
    units = [unit_of(n.split("[")[0]) for n in names]
    meta = {**meta, "input_units": units, "versions": versions()}
    text = json.dumps(meta, indent=2, default=_json_default)
    with warnings.catch_warnings():  # TorchScript is deprecated upstream but is the requested format
        warnings.simplefilter("ignore", DeprecationWarning)
        scripted = torch.jit.script(_Exported(net.cpu().eval(), names, units))
        torch.jit.save(scripted, str(out / "corrector.pt"), _extra_files={"meta.json": text})
    np.savez(out / "corrector.npz", **numpy_arrays(net))
    (out / "meta.json").write_text(text + "\n")
    return out


def _json_default(obj: Any) -> Any:
    if isinstance(obj, (np.integer, np.floating)):
        return obj.item()
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    raise TypeError(f"not JSON serialisable: {type(obj).__name__}")


def load_meta(bundle: str | Path) -> dict[str, Any]:
    """meta.json of a bundle, with a clear error if the directory is not one."""
    path = Path(bundle) / "meta.json"
    if not path.exists():
        raise SeadesignError(f"{bundle} is not a corrector bundle (no meta.json); create one with `seadesign train`")
    return json.loads(path.read_text())


def load_numpy(bundle: str | Path) -> NumpyCorrector:
    """The NumPy inference path of a bundle."""
    with np.load(Path(bundle) / "corrector.npz") as z:
        return NumpyCorrector(dict(z))


def load_torchscript(bundle: str | Path, freeze: bool = True) -> torch.jit.ScriptModule:
    """The TorchScript module of a bundle; frozen (faster single-sample calls) unless freeze=False."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        mod = torch.jit.load(str(Path(bundle) / "corrector.pt"), map_location="cpu").eval()
        return torch.jit.freeze(mod, preserved_attrs=["input_names", "input_units"]) if freeze else mod
