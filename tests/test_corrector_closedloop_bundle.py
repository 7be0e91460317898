"""The closed-loop policy's bundle: ONNX, NumPy and TorchScript give the PyTorch policy's commands to 1e-6 rad, with
the feedback branch doing real work; meta.json (also inside the ONNX file) carries inputs, units, normalisation, k,
the feedback bound and the simulator; the loaded bundle drives the knee as the policy in memory and passes `evaluate`."""

from __future__ import annotations

import numpy as np
import pytest
import torch
from conftest import REPO, require_module, thesis_spring

from seadesign.corrector.closedloop import run_closed_loop
from seadesign.corrector.closedloop_policy import MEASURED_INPUTS, runtime_corrector
from seadesign.corrector.closedloop_training import ClosedLoopSettings, train_closed_loop
from seadesign.corrector.export import load_meta, load_numpy, load_torchscript
from seadesign.corrector.reference import reference_features
from seadesign.corrector.runtime import ClosedLoopCorrector
from seadesign.corrector.workflow import evaluate_bundles, export_closedloop_bundle, load_corrector
from seadesign.errors import SeadesignError
from seadesign.twin import Trial
from seadesign.twin.torch_knee import protocol_tensors

INSTALL = "pip install 'seadesign[onnx]'"
SPRING_FILE = REPO / "studies" / "thesis_measured_spring.json"
ONE_EPOCH = ClosedLoopSettings(directions=("front", "back_right"), speeds=(0.15,), val_speeds=(0.075,), trial_s=3.0,
                               window_steps=50, max_epochs=1)

pytestmark = pytest.mark.usefixtures("one_torch_thread")


@pytest.fixture(scope="module")
def bundle(tmp_path_factory):
    """(bundle, result): one epoch of training, then the raw weights of the feedback's bounded layers spread (the
    bound still holds), so that the feedback moves the command by milliradians and every path must get it right."""
    for name in ("onnx", "onnxscript", "onnxruntime"):
        require_module(name, INSTALL)
    torch.set_num_threads(1)
    result = train_closed_loop(thesis_spring(), ONE_EPOCH)
    gen = torch.Generator().manual_seed(3)
    with torch.no_grad():
        fb = result.policy.feedback
        for layer in (fb.m_in, *fb.hidden, fb.out):
            layer.parametrizations.weight.original.add_(2.0 * torch.randn(layer.weight.shape, generator=gen))
    out = export_closedloop_bundle(result, SPRING_FILE, tmp_path_factory.mktemp("closedloop"), {"init": "test"})
    return out, result


def _rows(result) -> dict[str, np.ndarray]:
    """Flat inputs [x, m]: reference windows of two walks with measured inputs of the size seen in closed loop, and
    random rows over 3 standard deviations of the training windows with m up to 0.3 rad."""
    rng = np.random.default_rng(5)
    _, target, stance = protocol_tensors([Trial("front", 0.1, 4.0), Trial("rotate_right", 0.2, 4.0)])
    x = reference_features(np.moveaxis(target.numpy(), 2, 1), np.moveaxis(stance.numpy(), 2, 1),
                           thesis_spring()["k_Nm_per_rad"], result.settings.window).reshape(-1, 33)[::4]
    m = rng.uniform(-1, 1, (len(x), 2)) * [0.15, 0.05]
    ff = result.policy.ff
    mean, std = ff.x_mean.numpy(), ff.x_std.numpy()
    wide = mean + 3 * std * rng.uniform(-1, 1, (500, len(mean)))
    return {"realistic": np.hstack([x, m]).astype(np.float32),
            "random": np.hstack([wide, rng.uniform(-0.3, 0.3, (500, 2))]).astype(np.float32)}


def test_onnx_numpy_and_torchscript_give_the_policy_to_1e6_rad(bundle):
    from seadesign.onnx_corrector import load_onnx

    path, result = bundle
    ox, npc, ts = load_onnx(path), load_numpy(path), load_torchscript(path)
    for kind, z in _rows(result).items():
        x, m = torch.from_numpy(z[:, :-2]), torch.from_numpy(z[:, -2:])
        with torch.no_grad():
            ref = result.policy(x, m).numpy()
            feedback = ref - result.policy(x, torch.zeros_like(m)).numpy()
            scripted = ts(torch.from_numpy(z)).numpy()
        assert np.abs(feedback).max() > 1e-3, kind  # 1000 x the tolerance  # the feedback branch is exercised
        np.testing.assert_allclose(ox(z), ref, rtol=0, atol=1e-6, err_msg=f"{kind}: ONNX vs PyTorch")
        np.testing.assert_allclose(npc(z), ref, rtol=0, atol=1e-6, err_msg=f"{kind}: NumPy vs PyTorch")
        np.testing.assert_allclose(scripted, ref, rtol=0, atol=1e-6, err_msg=f"{kind}: TorchScript vs PyTorch")
        for i in (0, len(z) // 2):  # single vectors: float out
            assert abs(ox(z[i]) - ref[i]) <= 1e-6 and abs(npc(z[i]) - ref[i]) <= 1e-6
    with pytest.raises(SeadesignError, match="takes 35 inputs"):
        npc(np.zeros(33))


def test_meta_carries_inputs_units_normalisation_k_bound_and_simulator(bundle):
    from seadesign.onnx_corrector import load_onnx

    path, result = bundle
    meta = load_meta(path)
    assert load_onnx(path).meta == meta
    window = result.settings.window
    assert meta["model"] == "closedloop" and meta["reference"] == window.to_dict() and meta["init"] == "test"
    assert meta["inputs"] == [*window.feature_names(), *MEASURED_INPUTS] and meta["input_units"][-2:] == ["rad", "rad"]
    assert meta["input_units"][meta["inputs"].index("k_Nm_per_rad")] == "Nm/rad"
    assert meta["k_Nm_per_rad"] == thesis_spring()["k_Nm_per_rad"] and meta["control_rate_hz"] == 100.0
    assert meta["rate_time_s"] == 0.01
    bound = meta["feedback_lipschitz_bound_rad_per_rad"]
    assert bound == pytest.approx(result.policy.feedback_lipschitz_bound()) and 0.4 < bound <= 0.5 + 1e-6
    np.testing.assert_array_equal(np.float32(meta["normalisation"]["x_std"]), result.policy.ff.x_std.numpy())
    sim = meta["simulator"]
    assert sim["k_scales"] == [0.8, 1.0, 1.25] and sim["conditions"] == ["hanging", "ground"]
    assert sim["config"]["p_gain_Nm_per_rad"] == 60.0 and "ground_contact" in str(sim["effects"]["ground"])
    assert meta["training"]["epochs_run"] == 2 and meta["onnx"] == {"file": "corrector.onnx"}


def test_loaded_bundle_drives_the_knee_as_the_policy_and_evaluates_stable(bundle, tmp_path):
    """load_corrector gives the NumPy runtime of the bundle: in the simulator it sends exactly the commands of the
    policy in memory; `evaluate` runs it in closed loop only, with the loop-gain check."""
    path, result = bundle
    corrector, meta = load_corrector(path)
    assert isinstance(corrector, ClosedLoopCorrector) and corrector.name == meta["name"] == "closedloop"
    spring, trials = thesis_spring(), [Trial("back", 0.1, 4.0)]
    loaded = run_closed_loop(corrector, spring, trials, ground=True)
    memory = run_closed_loop(runtime_corrector(result.policy, spring["k_Nm_per_rad"]), spring, trials, ground=True)
    np.testing.assert_array_equal(loaded.command, memory.command)
    res = evaluate_bundles([path], [], tmp_path / "eval", closed_loop=("hanging",), trial_s=3.0)
    assert "open_loop" not in res and res["settings"]["not_judged_open_loop"] == ["closedloop"]
    row = next(r for r in res["closed_loop"] if r["candidate"] == "closedloop")
    assert not row["unstable_flag"] and 0 < row["modulus_margin"] < 1.0  # the feedback shows in the loop gain
