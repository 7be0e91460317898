"""Export a trained corrector: TorchScript (normalisation, input names and units baked in), ONNX
(for a robot without PyTorch) and a plain NumPy path, all with the same outputs. A bundle
directory holds:

- ``corrector.pt``: TorchScript; ``forward(x)`` maps raw SI inputs (B, d) to commands (B,) rad;
  ``input_names()`` / ``input_units()`` list the inputs; ``step(knee, target_rad, measured)`` runs
  it online (one knee, one control step: history window and right-knee mirroring inside,
  ``measured_names()`` lists the channels, ``reset()`` starts a trial); ``meta.json`` is
  embedded as an extra file.
- ``corrector.onnx``: the flat ``forward`` (inputs ``x`` (B, d) raw SI -> ``command_rad`` (B,),
  normalisation inside, dynamic batch), written through ``torch.onnx.export`` on ``torch.export``
  when the ``onnx`` extra is installed; every meta.json field is embedded as a JSON-encoded
  metadata property. Run it with `seadesign.onnx_corrector.load_onnx` (onnxruntime, no torch).
  Without the exporter the other files are still written and meta.json's ``onnx.skipped`` says why.
- ``corrector.npz``: weights and normalisation for `NumpyCorrector` (or, for a policy trained through
  the closed loop, `NumpyClosedLoop`); `load_numpy` picks the one that fits.
- ``meta.json``: dataset spec, model kind, k, inputs and units, normalisation, split, training
  settings and curve, whatever else the caller records (e.g. simulator and control rate),
  ONNX status, versions.
"""


import importlib
import json
import logging
import platform
import warnings
from importlib import metadata
from pathlib import Path
from typing import Any

import numpy as np
import torch
from torch import nn

from seadesign import __version__
from seadesign.corrector.dataset import DatasetSpec
from seadesign.corrector.modalities import MIRRORED_CHANNELS, channels, unit_of
from seadesign.corrector.models import CorrectorNet, MLPCore, SiameseCore
from seadesign.errors import SeadesignError

LEAKY_SLOPE = 0.01  # torch.nn.LeakyReLU default
ONNX_FILE = "corrector.onnx"
ONNX_INSTALL = "pip install 'seadesign[onnx]'"


class _Forward(nn.Module):
    """TorchScript wrapper of a network whose online inputs are built outside (the reference-window
    families: `reference.ReferenceBuffer`): `forward` on flat raw inputs, with their names and units."""

    names: list[str]
    units: list[str]

    def __init__(self, net: nn.Module, names: list[str], units: list[str]) -> None:
        super().__init__()
        self.net, self.names, self.units = net, names, units

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return self.net(x)

    @torch.jit.export
    def input_names(self) -> list[str]:
        return self.names

    @torch.jit.export
    def input_units(self) -> list[str]:
        return self.units


class _Exported(_Forward):
    """TorchScript wrapper: the network on flat raw inputs (`forward`), and the online path
    `step` that keeps each knee's history window and applies the right knee's mirroring, exactly
    as the training dataset laid the inputs out (`FeatureBuilder`)."""

    measured: list[str]
    siamese: bool
    n_channels: int
    hall: int

    def __init__(self, net: CorrectorNet, names: list[str], units: list[str], spec: DatasetSpec) -> None:
        super().__init__(net, names, units)
        self.siamese = isinstance(net.core, SiameseCore)
        chans = list(channels(spec.modalities))
        self.n_channels = len(chans)
        self.measured = chans + (["hall_pos_rad"] if self.siamese and "hall_pos_rad" not in chans else [])
        self.hall = self.measured.index("hall_pos_rad") if self.siamese else -1
        flip = [-1.0 if n.split("@")[0] in MIRRORED_CHANNELS else 1.0 for n in spec.feature_names()]
        self.register_buffer("flip_right", torch.tensor(flip if spec.positive else [1.0] * len(flip)))
        self.register_buffer("sign_right", torch.tensor(-1.0 if spec.positive else 1.0))
        self.register_buffer("past", torch.zeros(2, spec.history + 1, len(self.measured)))
        self.register_buffer("count", torch.zeros(2, dtype=torch.long))

    @torch.jit.export
    def measured_names(self) -> list[str]:
        """Channels `step` takes each control step, in order (robot frame, SI)."""
        return self.measured

    @torch.jit.export
    def reset(self) -> None:
        """Forget both knees' history (start of a trial)."""
        self.past.zero_()
        self.count.zero_()

    @torch.jit.export
    def step(self, knee: int, target_rad: float, measured: torch.Tensor) -> float:
        """One control step of one knee (0 left, 1 right): target (rad) and the measured_names
        channels -> motor command (rad), robot frame."""
        if knee != 0 and knee != 1:
            raise ValueError("knee must be 0 (left) or 1 (right)")
        if measured.shape[0] != len(self.measured):
            raise ValueError("measured must hold the channels listed by measured_names()")
        m = measured.to(torch.float32)
        if int(self.count[knee]) == 0:
            self.past[knee] = m.expand(self.past.shape[1], m.shape[0])
        else:
            self.past[knee, 1:] = self.past[knee, :-1].clone()
            self.past[knee, 0] = m
        self.count[knee] += 1
        window = self.past[knee, :, : self.n_channels].reshape(-1)
        flip = self.flip_right if knee == 1 else torch.ones_like(self.flip_right)
        x = torch.cat([torch.tensor([target_rad], dtype=torch.float32), window]) * flip
        if self.siamese:  # x_t: the measured Hall position as target (thesis 6.2.3)
            x = torch.cat([torch.cat([self.past[knee, 0, self.hall : self.hall + 1], window]) * flip, x])
        u = self.net(x.unsqueeze(0))[0]
        return float(u * self.sign_right) if knee == 1 else float(u)


def versions() -> dict[str, str]:
    """Package versions (the ONNX ones where installed) and machine recorded with every model and result."""
    found = {"seadesign": __version__, "torch": torch.__version__, "numpy": np.__version__,
             "python": platform.python_version(), "machine": f"{platform.system()} {platform.machine()}"}
    for name in ("onnx", "onnxscript", "onnxruntime"):
        try:
            found[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            pass
    return found


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


class NumpyClosedLoop:
    """A policy trained through the closed loop (`closedloop_training`) in NumPy (float64):
    command = ff(x) + L [h(m, x) - h(0, x)] (rad, flexion) from the reference window x (d) and the measured
    inputs m (2, rad); arrays from `closedloop_policy.policy_arrays` (standardisation folded in)."""

    def __init__(self, arrays: dict[str, np.ndarray]) -> None:
        a = {k: np.asarray(v, dtype=np.float64) for k, v in arrays.items()}
        self.first_W, self.first_b, self.n_ff = a["first_W"], a["first_b"], int(a["n_ff"])
        self.ff_hidden = [(a[f"ff_W{i}"], a[f"ff_b{i}"]) for i in range(int(a["n_ff_hidden"]))]
        self.fb_hidden = [(a[f"fb_W{i}"], a[f"fb_b{i}"]) for i in range(int(a["n_fb_hidden"]))]
        self.base_w, self.ff_out_W, self.ff_out_b = a["base_w"], a["ff_out_W"], float(a["ff_out_b"])
        self.m_W, self.fb_out_W, self.rate_time_s = a["m_W"], a["fb_out_W"], float(a["rate_time_s"])
        self.d = self.first_W.shape[1]

    def command(self, x: np.ndarray, m: np.ndarray) -> np.ndarray:
        """Commands (...,) rad from windows x (..., d) and measured inputs m (..., 2) rad."""
        a = x @ self.first_W.T + self.first_b
        z = a[..., : self.n_ff]
        z = np.maximum(z, LEAKY_SLOPE * z)
        for W, b in self.ff_hidden:
            z = z @ W.T + b
            z = np.maximum(z, LEAKY_SLOPE * z)
        ctx = a[..., self.n_ff:]
        h, h0 = np.tanh(m @ self.m_W.T + ctx), np.tanh(ctx)
        for W, b in self.fb_hidden:
            h, h0 = np.tanh(h @ W.T + b), np.tanh(h0 @ W.T + b)
        return x @ self.base_w + z @ self.ff_out_W + self.ff_out_b + (h - h0) @ self.fb_out_W

    def __call__(self, z: np.ndarray) -> np.ndarray | float:
        """Raw inputs z = [x, m] (d + 2,) or (B, d + 2), the bundle's input order -> command(s), rad."""
        z = np.asarray(z, dtype=np.float64)
        if z.shape[-1] != self.d + 2:
            raise SeadesignError(f"the closed-loop policy takes {self.d + 2} inputs (reference window, then the "
                                 f"two measured ones), got shape {z.shape}")
        u = self.command(z[..., : self.d], z[..., self.d:])
        return float(u) if z.ndim == 1 else u


def normalisation(net: CorrectorNet) -> dict[str, Any]:
    """u = base_w . x + y_mean + y_std * core((x - x_mean) / x_std): x_mean, x_std in the input
    units, base_w in rad per input unit, y_mean and y_std in rad."""
    return {k: getattr(net, k).detach().cpu().float().tolist() for k in ("x_mean", "x_std", "y_mean", "y_std", "base_w")}


def onnx_exporter_missing() -> str | None:
    """Why corrector.onnx cannot be written here (the missing packages and the install command),
    or None when the exporter's packages import."""
    missing = []
    for name in ("onnx", "onnxscript"):
        try:
            importlib.import_module(name)
        except ImportError:
            missing.append(name)
    if not missing:
        return None
    return f"{' and '.join(missing)} not installed, so no {ONNX_FILE} was written; install with {ONNX_INSTALL}"


def export_onnx(net: nn.Module, meta: dict[str, Any], path: str | Path) -> Path:
    """Write the network's flat forward as ONNX (input ``x`` (B, d) raw SI, d = len(meta["inputs"]), output
    ``command_rad`` (B,), dynamic batch) with every `meta` field as a JSON metadata property."""
    import onnx

    d = len(meta["inputs"])
    log = logging.getLogger("torch.onnx")  # warns once per export that torchvision's ops are absent
    level = log.level
    log.setLevel(logging.ERROR)
    try:
        with warnings.catch_warnings():  # torch.export's pytree internals warn about their own API
            warnings.simplefilter("ignore", FutureWarning)
            program = torch.onnx.export(net.cpu().eval(), (torch.zeros(2, d),), input_names=["x"],
                                        output_names=["command_rad"], dynamic_shapes=({0: torch.export.Dim("batch")},),
                                        dynamo=True, verbose=False)
    finally:
        log.setLevel(level)
    proto = program.model_proto
    proto.doc_string = "seadesign corrector: raw SI inputs x (B, d) -> motor position command (B,), rad"
    onnx.helper.set_model_props(proto, {k: json.dumps(v, default=_json_default) for k, v in meta.items()})
    onnx.checker.check_model(proto)
    onnx.save_model(proto, str(path))  # one file: the weights are far below the 2 GB external-data limit
    return Path(path)


def export_bundle(net: nn.Module, meta: dict[str, Any], out_dir: str | Path,
                  arrays: dict[str, np.ndarray] | None = None) -> Path:
    """Write corrector.pt, corrector.onnx (when the exporter is installed), corrector.npz and
    meta.json into `out_dir`; meta["dataset"], when present, is the DatasetSpec as a dict (it fixes the
    online path's history and mirroring; without it corrector.pt has `forward` only). Other fields
    (k, simulator settings, control rate) are kept. `net`: a `CorrectorNet`, or (with the NumPy path's
    `arrays` and meta["normalisation"] given) any module mapping raw inputs (B, d) to commands (B,) rad."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    names = list(meta["inputs"])
    units = [unit_of(n.split("[")[0]) for n in names]
    skipped = onnx_exporter_missing()
    meta = {**meta, "input_units": units, "normalisation": meta["normalisation"] if arrays else normalisation(net),
            "onnx": {"skipped": skipped} if skipped else {"file": ONNX_FILE}, "versions": versions()}
    if skipped is None:
        export_onnx(net, meta, out / ONNX_FILE)
    else:
        (out / ONNX_FILE).unlink(missing_ok=True)
    text = json.dumps(meta, indent=2, default=_json_default)
    with warnings.catch_warnings():  # TorchScript is deprecated upstream but is the requested format
        warnings.simplefilter("ignore", DeprecationWarning)
        module = _Exported(net.cpu().eval(), names, units, DatasetSpec.from_dict(meta["dataset"])) \
            if "dataset" in meta else _Forward(net.cpu().eval(), names, units)
        scripted = torch.jit.script(module)
        torch.jit.save(scripted, str(out / "corrector.pt"), _extra_files={"meta.json": text})
    np.savez(out / "corrector.npz", **(arrays or numpy_arrays(net)))
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


def load_numpy(bundle: str | Path) -> NumpyCorrector | NumpyClosedLoop:
    """The NumPy inference path of a bundle (a closed-loop policy's when its arrays are one's)."""
    with np.load(Path(bundle) / "corrector.npz") as z:
        arrays = dict(z)
    return NumpyClosedLoop(arrays) if "fb_out_W" in arrays else NumpyCorrector(arrays)


def load_torchscript(bundle: str | Path, freeze: bool = True) -> torch.jit.ScriptModule:
    """The TorchScript module of a bundle; unless freeze=False, frozen and passed through
    `torch.jit.optimize_for_inference` (forward and step), which makes single-sample calls faster with the
    same outputs (measured in docs/validation/corrector.md)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        mod = torch.jit.load(str(Path(bundle) / "corrector.pt"), map_location="cpu").eval()
        if not freeze:
            return mod
        online = ["measured_names", "reset", "step"] if hasattr(mod, "step") else []
        frozen = torch.jit.freeze(mod, preserved_attrs=["input_names", "input_units", *online])
        return torch.jit.optimize_for_inference(frozen, other_methods=["step"] if online else None)
