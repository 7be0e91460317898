"""Corrector datasets, splits, training and export on synthetic data (no ../shared needed)."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from seadesign.corrector.dataset import CorrectorDataset, DatasetSpec, FeatureBuilder, build_dataset
from seadesign.corrector.export import export_bundle, input_list, load_numpy, load_torchscript
from seadesign.corrector.modalities import COMBINATIONS, MODALITIES, channels
from seadesign.corrector.models import MODEL_KINDS
from seadesign.corrector.splits import make_split, random_split, recording_split, time_block_split
from seadesign.corrector.synthetic import linear_spring_recording
from seadesign.corrector.train import TrainConfig, fit
from seadesign.errors import SeadesignError

K = 9.106
FAST = dict(max_epochs=15, patience=5, batch_size=1024)


@pytest.fixture(scope="module")
def recs():
    return [linear_spring_recording(K, duration_s=12.0, seed=s, name=f"syn{s}") for s in range(3)]


def test_eleven_combinations_and_shapes(recs):
    assert len(COMBINATIONS) == 11
    for name, mods in COMBINATIONS.items():
        spec = DatasetSpec(task="thesis", modalities=name, history=2)
        ds = build_dataset(recs, spec)
        d = 1 + 3 * len(channels(mods))
        n = sum(2 * (len(r.time_s) - 1 - 2) for r in recs)  # both knees, t = history .. T-2
        assert ds.X.shape == (n, d) and ds.X_next.shape == (n, d) and ds.y.shape == (n,)
        assert len(ds.feature_names) == d and ds.feature_names[0] == "target_rad"


def test_thesis_task_rows_match_definition(recs):
    """thesis: x_t = [hall_t, channels_t], y = motor_t+1; positive mirrors the right knee."""
    rec = recs[0]
    ds = build_dataset([rec], DatasetSpec(task="thesis", modalities="velocity_effort", positive=True))
    right = np.flatnonzero(ds.knee == 1)[5]
    t = ds.step[right]
    ch = rec.knees["right"]
    assert ds.X[right, 0] == -ch["hall_pos_rad"][t]
    assert ds.X[right, ds.feature_names.index("effort_Nm")] == -ch["effort_Nm"][t]
    assert ds.y[right] == -ch["motor_pos_rad"][t + 1]
    inv = build_dataset([rec], DatasetSpec(task="inverse", modalities="velocity_effort", positive=False))
    assert inv.X[right, 0] == ch["hall_pos_rad"][t + 1] and inv.y[right] == ch["motor_pos_rad"][t + 1]


def test_online_feature_builder_reproduces_dataset_rows(recs):
    rec = recs[1]
    spec = DatasetSpec(task="inverse", modalities="all", history=3, positive=True)
    ds = build_dataset([rec], spec)
    b = FeatureBuilder(spec, "right")
    names = channels(tuple(MODALITIES))
    rows = {int(s): i for i, s in enumerate(ds.step) if ds.knee[i] == 1}
    for t in range(40):
        b.push({c: rec.knees["right"][c][t] for c in names})
        if t in rows:
            x = b.inputs(rec.knees["right"]["hall_pos_rad"][t + 1])
            np.testing.assert_array_equal(x, ds.X[rows[t]])


def test_unknown_modality_and_task_are_refused():
    with pytest.raises(SeadesignError, match="modality"):
        DatasetSpec(modalities="velocity,torque")
    with pytest.raises(SeadesignError, match="--task"):
        DatasetSpec(task="future")


def test_time_block_split_has_no_overlap_and_guard_gaps(recs):
    ds = build_dataset(recs, DatasetSpec(history=3))
    sp = time_block_split(ds, n_blocks=8, val_blocks=2, test_blocks=2, seed=1)
    sets = [set(sp.train), set(sp.val), set(sp.test)]
    assert not (sets[0] & sets[1]) and not (sets[0] & sets[2]) and not (sets[1] & sets[2])
    gap = sp.settings["guard_gap_samples"]
    assert gap >= ds.spec.history + 2
    for a, b in ((sp.train, sp.test), (sp.train, sp.val), (sp.val, sp.test)):
        for r in np.unique(ds.recording):
            sa = ds.step[a][ds.recording[a] == r]
            sb = ds.step[b][ds.recording[b] == r]
            # no window [t-history, t+1] of one set shares a sample with one of the other
            dist = np.abs(sa[:, None] - sb[None, :]).min()
            assert dist >= ds.spec.history + 2
    # both knees of one instant stay together
    for idx in (sp.train, sp.test):
        keys_l = {(r, s) for r, s, k in zip(ds.recording[idx], ds.step[idx], ds.knee[idx]) if k == 0}
        keys_r = {(r, s) for r, s, k in zip(ds.recording[idx], ds.step[idx], ds.knee[idx]) if k == 1}
        assert keys_l == keys_r


def test_recording_and_random_splits(recs):
    ds = build_dataset(recs, DatasetSpec())
    sp = recording_split(ds, test=["syn1"])
    assert set(ds.recording[sp.test]) == {1} and 1 not in set(ds.recording[sp.train]) | set(ds.recording[sp.val])
    rnd = random_split(ds, 0.8, seed=0)
    assert abs(len(rnd.train) - 0.8 * len(ds)) <= 1 and rnd.name == "random"
    with pytest.raises(SeadesignError, match="not among"):
        recording_split(ds, test=["nope"])
    with pytest.raises(SeadesignError, match="--split"):
        make_split(ds, "shuffled")


@pytest.mark.parametrize("model", ["mlp", "siamese"])
def test_training_is_deterministic(recs, model):
    ds = build_dataset(recs[:1], DatasetSpec())
    sp = time_block_split(ds)
    a = fit(ds, sp, K, TrainConfig(model=model, seed=3, **FAST))
    b = fit(ds, sp, K, TrainConfig(model=model, seed=3, **FAST))
    c = fit(ds, sp, K, TrainConfig(model=model, seed=4, **FAST))
    for (ka, va), (_, vb) in zip(a.net.state_dict().items(), b.net.state_dict().items()):
        assert torch.equal(va, vb), ka
    assert [r["val_mse_rad2"] for r in a.curve] == [r["val_mse_rad2"] for r in b.curve]
    assert not torch.equal(a.net.core.state_dict()[next(iter(a.net.core.state_dict()))],
                           c.net.core.state_dict()[next(iter(c.net.core.state_dict()))])


def test_mlp_learns_known_mapping():
    """y = target + 0.1 sin(2 effort) + 0.05 vel on random inputs: held-out RMSE < 0.01 rad (std of y - target ~ 0.08)."""
    rng = np.random.default_rng(0)
    n = 6000
    X = np.column_stack([rng.uniform(0.8, 1.6, n), rng.normal(0, 0.5, n), rng.uniform(-2, 2, n)])
    y = X[:, 0] + 0.1 * np.sin(2 * X[:, 2]) + 0.05 * X[:, 1]
    spec = DatasetSpec(modalities=("motor_vel", "effort"))
    zeros = np.zeros(n, int)
    ds = CorrectorDataset(spec, ("target_rad", "motor_vel_rad_per_s", "effort_Nm"), X, X, y, zeros, zeros,
                          np.arange(n), np.arange(n) * 0.01, np.ones(n), ("known",))
    sp = time_block_split(ds, seed=0)
    res = fit(ds, sp, K, TrainConfig(model="mlp", max_epochs=150, patience=20, batch_size=256, lr=3e-3))
    with torch.no_grad():
        pred = res.net(torch.as_tensor(X[sp.test], dtype=torch.float32)).numpy()
    rmse = float(np.sqrt(np.mean((pred - y[sp.test]) ** 2)))
    assert rmse < 0.01, rmse


def test_history_model_needs_a_window(recs):
    ds = build_dataset(recs[:1], DatasetSpec(history=0))
    with pytest.raises(SeadesignError, match="--history"):
        fit(ds, time_block_split(ds), K, TrainConfig(model="history", **FAST))


def test_residual_model_needs_effort(recs):
    ds = build_dataset(recs[:1], DatasetSpec(modalities="velocity"))
    with pytest.raises(SeadesignError, match="effort"):
        fit(ds, time_block_split(ds), K, TrainConfig(model="residual", **FAST))


@pytest.mark.parametrize("model", MODEL_KINDS)
def test_torchscript_and_numpy_agree(recs, model, tmp_path):
    spec = DatasetSpec(modalities="velocity_effort", history=2 if model == "history" else 0)
    ds = build_dataset(recs[:1], spec)
    res = fit(ds, time_block_split(ds), K, TrainConfig(model=model, max_epochs=3, patience=3))
    siamese = model == "siamese"
    names = input_list(ds.feature_names, siamese)
    bundle = export_bundle(res.net, {"inputs": names, "model": model, "dataset": spec.to_dict()}, tmp_path / model)
    ts, npc = load_torchscript(bundle), load_numpy(bundle)
    X = np.concatenate([ds.X, ds.X_next], axis=1) if siamese else ds.X
    X = X.astype(np.float32)
    with torch.no_grad():
        a = ts(torch.from_numpy(X)).numpy()
        ref = res.net(torch.from_numpy(X)).numpy()
    b = npc(X)
    np.testing.assert_allclose(a, ref, atol=1e-6)
    np.testing.assert_allclose(b, a, atol=2e-6)
    assert abs(npc(X[7]) - a[7]) < 2e-6
    assert ts.input_names() == names
    assert ts.input_units()[0] == "rad" and "Nm" in ts.input_units()


@pytest.mark.parametrize("model", ["history", "siamese"])
def test_torchscript_step_runs_history_and_mirroring_like_the_online_builder(recs, model, tmp_path):
    """The exported step() (history window and right-knee mirroring inside the TorchScript
    module) gives the NumPy corrector driven through FeatureBuilder, for both knees."""
    from seadesign.corrector.runtime import NetCorrector

    spec = DatasetSpec(modalities="velocity_effort", history=3 if model == "history" else 0, positive=True)
    ds = build_dataset(recs[:1], spec)
    res = fit(ds, time_block_split(ds), K, TrainConfig(model=model, max_epochs=3, patience=3))
    meta = {"inputs": input_list(ds.feature_names, model == "siamese"), "model": model, "dataset": spec.to_dict()}
    bundle = export_bundle(res.net, meta, tmp_path / model)
    ts = load_torchscript(bundle)
    online = NetCorrector(load_numpy(bundle), spec, model)
    rec = recs[1]
    names = ts.measured_names()
    assert names[: len(channels(spec.modalities))] == list(channels(spec.modalities))
    for i in range(40):
        for k, knee in enumerate(("left", "right")):
            measured = {c: float(rec.knees[knee][c][i]) for c in rec.knees[knee]}
            target = float(rec.knees[knee]["hall_pos_rad"][i + 1])
            ref = online.command(knee, target, measured, 0.01)
            got = ts.step(k, target, torch.tensor([measured[c] for c in names], dtype=torch.float64))
            assert got == pytest.approx(ref, abs=2e-5), (i, knee)
    ts.reset()
    online.reset()
    m0 = {c: float(rec.knees["right"][c][5]) for c in rec.knees["right"]}
    assert ts.step(1, 0.3, torch.tensor([m0[c] for c in names])) == pytest.approx(online.command("right", 0.3, m0, 0.01), abs=2e-5)
    with pytest.raises(torch.jit.Error, match="knee must be"):
        ts.step(2, 0.3, torch.tensor([m0[c] for c in names]))
