"""ONNX export of corrector bundles: corrector.onnx under ONNX Runtime gives the PyTorch module's
and the NumPy path's commands to 1e-6 rad, carries meta.json as metadata, runs without torch;
a machine without the exporter still gets the other files and the reason in meta.json.

The ONNX tests skip when onnx / onnxscript / onnxruntime are missing, but fail under CI=true
(the `test` extra installs them)."""

from __future__ import annotations

import json
import logging
import os
import subprocess
import sys
import warnings

import numpy as np
import pytest
import torch

from conftest import REPO, require_module
from seadesign.corrector.dataset import DatasetSpec, build_dataset
from seadesign.corrector.export import export_bundle, input_list, load_meta, load_numpy, load_torchscript
from seadesign.corrector.splits import time_block_split
from seadesign.corrector.synthetic import linear_spring_recording
from seadesign.corrector.train import TrainConfig, fit
from seadesign.errors import SeadesignError
from seadesign.onnx_corrector import load_onnx

K = 9.106
MODELS = ("mlp", "residual", "siamese")
INSTALL = "pip install 'seadesign[onnx]'"
SIMULATOR = {"name": "seadesign.twin.knee", "dt_s": 0.001, "load": "hanging"}


def _require_exporter() -> None:
    for name in ("onnx", "onnxscript", "onnxruntime"):
        require_module(name, INSTALL)


def _train(model: str):
    recs = [linear_spring_recording(K, duration_s=8.0, seed=s, name=f"syn{s}") for s in range(2)]
    spec = DatasetSpec(modalities="velocity_effort", positive=True)
    ds = build_dataset(recs, spec)
    res = fit(ds, time_block_split(ds), K, TrainConfig(model=model, max_epochs=3, patience=3, seed=1))
    siamese = model == "siamese"
    meta = {"inputs": input_list(ds.feature_names, siamese), "model": model, "dataset": spec.to_dict(),
            "k_Nm_per_rad": K, "simulator": SIMULATOR, "control_rate_hz": 1000.0}
    X = np.concatenate([ds.X, ds.X_next], axis=1) if siamese else ds.X
    return res.net, meta, X.astype(np.float32)


class _Records(logging.Handler):
    def __init__(self) -> None:
        super().__init__(logging.WARNING)
        self.records: list[logging.LogRecord] = []

    def emit(self, record: logging.LogRecord) -> None:
        self.records.append(record)


TORCH_LOGGERS = ("torch", "torch.onnx")  # torch.onnx does not propagate to torch
EXPORT_NOISE: list[str] = []  # warnings and log records seen while the bundles fixture exported


@pytest.fixture(scope="module")
def bundles(tmp_path_factory):
    """model -> (bundle, trained net, realistic inputs (dataset rows), meta given to the export)."""
    _require_exporter()
    out = {}
    for model in MODELS:
        net, meta, X = _train(model)
        handler = _Records()
        loggers = [logging.getLogger(name) for name in TORCH_LOGGERS]
        for log in loggers:
            log.addHandler(handler)
        try:
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always")
                out[model] = (export_bundle(net, meta, tmp_path_factory.mktemp(model)), net, X, meta)
        finally:
            for log in loggers:
                log.removeHandler(handler)
        EXPORT_NOISE.extend([str(w.message) for w in caught] + [r.getMessage() for r in handler.records])
    return out


def test_export_is_quiet(bundles):
    """No deprecation warnings (TorchScript, torch.export internals) and no exporter log lines."""
    assert EXPORT_NOISE == []


def _inputs(net, X: np.ndarray) -> dict[str, np.ndarray]:
    """Realistic rows and random ones spread over 3 standard deviations of the training inputs."""
    rng = np.random.default_rng(7)
    mean, std = net.x_mean.numpy(), net.x_std.numpy()
    wide = (mean + 3 * std * rng.uniform(-1, 1, (500, len(mean)))).astype(np.float32)
    return {"realistic": X[:: max(1, len(X) // 2000)], "random": wide}


@pytest.mark.parametrize("model", MODELS)
def test_onnx_torch_and_numpy_agree_to_1e6_rad(bundles, model):
    bundle, net, X, _ = bundles[model]
    if model == "residual":
        assert np.count_nonzero(net.base_w.numpy()) == 2  # target + effort / k: the base term is exercised
    ox, npc, ts = load_onnx(bundle), load_numpy(bundle), load_torchscript(bundle)
    for kind, x in _inputs(net, X).items():
        with torch.no_grad():
            ref = net(torch.from_numpy(x)).numpy()
            scripted = ts(torch.from_numpy(x)).numpy()
        got = ox(x)
        assert got.shape == ref.shape and got.dtype == np.float32
        np.testing.assert_allclose(got, ref, rtol=0, atol=1e-6, err_msg=f"{model} {kind}: ONNX vs PyTorch")
        np.testing.assert_allclose(got, npc(x), rtol=0, atol=1e-6, err_msg=f"{model} {kind}: ONNX vs NumPy")
        np.testing.assert_allclose(got, scripted, rtol=0, atol=1e-6, err_msg=f"{model} {kind}: ONNX vs TorchScript")
        for i in (0, len(x) // 2, len(x) - 1):  # single vectors: float out, as NumpyCorrector
            single = ox(x[i])
            assert isinstance(single, float) and abs(single - ref[i]) <= 1e-6 and abs(single - npc(x[i])) <= 1e-6
            assert ox(x[i].astype(np.float64).tolist()) == single
        np.testing.assert_allclose(ox(x[:1]), ref[:1], rtol=0, atol=1e-6)  # batch of one


def test_onnx_graph_has_dynamic_batch_and_single_call_session(bundles):
    import onnx

    proto = onnx.load(str(bundles["mlp"][0] / "corrector.onnx"))
    (x,) = proto.graph.input
    dims = x.type.tensor_type.shape.dim
    assert x.name == "x" and dims[0].dim_param and dims[1].dim_value == len(bundles["mlp"][3]["inputs"])
    assert [o.name for o in proto.graph.output] == ["command_rad"]
    assert not (bundles["mlp"][0] / "corrector.onnx.data").exists()  # one self-contained file
    ort = require_module("onnxruntime", INSTALL)
    opts = load_onnx(bundles["mlp"][0]).session.get_session_options()  # tuned for single calls in a 1 kHz loop
    assert opts.intra_op_num_threads == 1 and opts.execution_mode == ort.ExecutionMode.ORT_SEQUENTIAL
    assert opts.graph_optimization_level == ort.GraphOptimizationLevel.ORT_ENABLE_ALL


@pytest.mark.parametrize("model", MODELS)
def test_onnx_metadata_equals_meta_json(bundles, model):
    bundle, net, _, given = bundles[model]
    meta = load_meta(bundle)
    carried = load_onnx(bundle).meta
    assert carried == meta
    assert carried["inputs"] == given["inputs"] and carried["k_Nm_per_rad"] == K
    assert carried["simulator"] == SIMULATOR and carried["control_rate_hz"] == 1000.0
    assert carried["input_units"][0] == "rad" and "Nm" in carried["input_units"]
    assert len(carried["input_units"]) == len(carried["inputs"])
    norm = carried["normalisation"]
    for name in ("x_mean", "x_std", "base_w", "y_mean", "y_std"):
        np.testing.assert_array_equal(np.float32(norm[name]), getattr(net, name).numpy(), err_msg=name)
    assert carried["onnx"] == {"file": "corrector.onnx"} and "onnxruntime" in carried["versions"]


def test_onnx_runtime_runs_without_torch(bundles):
    """The robot's path: a fresh interpreter that loads and runs corrector.onnx never imports torch."""
    bundle, _, X, _ = bundles["mlp"]
    code = ("import json, sys; from seadesign.onnx_corrector import load_onnx; "
            f"c = load_onnx({str(bundle)!r}); u = c({X[3].tolist()!r}); "
            "print(json.dumps({'u': u, 'torch': 'torch' in sys.modules}))")
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(REPO), os.environ.get("PYTHONPATH", "")])}
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, check=True, timeout=120)
    result = json.loads(out.stdout)
    assert result["torch"] is False
    assert abs(result["u"] - load_numpy(bundle)(X[3])) <= 1e-6


def test_onnx_refuses_bad_inputs_and_missing_runtime(bundles, monkeypatch):
    bundle = bundles["siamese"][0]
    ox = load_onnx(bundle)
    d = len(ox.input_names)
    for bad in (np.zeros(d - 1), np.zeros((2, d + 1)), np.zeros((1, 2, d))):
        with pytest.raises(SeadesignError, match=f"takes {d} inputs .*target_rad\\[t\\]"):
            ox(bad)
    monkeypatch.setitem(sys.modules, "onnxruntime", None)
    with pytest.raises(SeadesignError, match=r"needs onnxruntime; install with pip install 'seadesign\[onnx\]'"):
        load_onnx(bundle)


def test_bundle_without_the_onnx_exporter(tmp_path, monkeypatch):
    """Missing onnxscript: the other files are written, meta.json says why and what to install,
    load_onnx repeats it; a stale corrector.onnx from an earlier export is removed."""
    net, meta, X = _train("mlp")
    (tmp_path / "corrector.onnx").write_bytes(b"stale")
    monkeypatch.setitem(sys.modules, "onnxscript", None)
    bundle = export_bundle(net, meta, tmp_path)
    assert sorted(p.name for p in bundle.iterdir()) == ["corrector.npz", "corrector.pt", "meta.json"]
    reason = load_meta(bundle)["onnx"]["skipped"]
    assert "onnxscript not installed" in reason and INSTALL in reason and "onnx and" not in reason
    with pytest.raises(SeadesignError, match="was not exported: onnxscript not installed"):
        load_onnx(bundle)
    with torch.no_grad():
        ref = net(torch.from_numpy(X[:50])).numpy()
    np.testing.assert_allclose(load_numpy(bundle)(X[:50]), ref, rtol=0, atol=1e-6)
    np.testing.assert_allclose(load_torchscript(bundle)(torch.from_numpy(X[:50])).detach().numpy(), ref, rtol=0, atol=1e-6)
