"""The closed-loop policy, trained through the closed loop: the feedback's Lipschitz bound holds, gradients reach both
branches through the torch knee, training lowers the validation error and is seeded, the NumPy runtime is the
policy; slow: a corrector trained from scratch meets the closed-loop goal in every cell of the protocol."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import torch
from conftest import thesis_spring

from seadesign.corrector.closedloop import closed_loop_table, run_closed_loop
from seadesign.corrector.closedloop_policy import (FEEDBACK_LIPSCHITZ_RAD_PER_RAD, ClosedLoopPolicy, FeedbackBranch,
                                                   runtime_corrector)
from seadesign.corrector.closedloop_training import ClosedLoopSettings, _batch, train_closed_loop, window_policy
from seadesign.corrector.goal import goal_table
from seadesign.corrector.reference import Preview, ReferenceBuffer, ReferenceWindow, reference_features
from seadesign.corrector.runtime import FeedForward, HallPI, NoCorrection
from seadesign.errors import SeadesignError
from seadesign.twin import KneeConfig, Trial, configure_chain, knee_effects
from seadesign.twin.knee import SIGN
from seadesign.twin.torch_knee import TorchKnee, protocol_tensors, rollout

WINDOW = ReferenceWindow()
QUIET = ["hall_noise=off", "hall_quantisation=off", "motor_quantisation=off", "effort_noise=off"]


pytestmark = pytest.mark.usefixtures("one_torch_thread")


def _policy(seed: int = 0, spread: float = 1.0) -> tuple[ClosedLoopPolicy, np.ndarray]:
    """A policy on random reference windows, its weights pushed by `spread` (so the bound has work to do)."""
    rng = np.random.default_rng(seed)
    X = rng.normal(size=(400, len(WINDOW.feature_names()))) + 1.0
    policy = ClosedLoopPolicy.from_scratch(X, WINDOW, seed=seed)
    gen = torch.Generator().manual_seed(seed)
    with torch.no_grad():
        for p in policy.parameters():
            p.add_(spread * torch.randn(p.shape, generator=gen))
    return policy, X


def _gains(policy: ClosedLoopPolicy, x: torch.Tensor, m: torch.Tensor) -> torch.Tensor:
    """||d command / d m|| (rad/rad) per row (rows are independent: the sum's gradient is each row's)."""
    m = m.clone().requires_grad_(True)
    return torch.autograd.grad(policy(x, m).sum(), m)[0].norm(dim=1)


def test_feedback_gain_is_bounded_and_zero_at_zero_error():
    """||d command / d m|| <= L (rad/rad) on random inputs (m up to 0.5 rad) with large raw weights; no error,
    no feedback."""
    policy, X = _policy(spread=3.0)
    x = torch.as_tensor(X[:256], dtype=torch.float32)
    m = 0.5 * torch.randn(256, 2, generator=torch.Generator().manual_seed(1))
    assert float(_gains(policy, x, m).max()) <= policy.feedback_lipschitz_bound() + 1e-6
    assert policy.feedback_lipschitz_bound() <= FEEDBACK_LIPSCHITZ_RAD_PER_RAD + 1e-6
    with torch.no_grad():
        np.testing.assert_allclose(policy(x, torch.zeros_like(m)).numpy(), policy.ff(x).numpy(), atol=1e-6)


def _aligned_feedback(policy: ClosedLoopPolicy) -> None:
    """Give `policy` a one-layer feedback without reference context, raw weights 5 e1 e1^T and 5 e1^T: its gain is
    L along the Hall error at m = 0 (25 L without the bound)."""
    policy.feedback = FeedbackBranch(len(WINDOW.feature_names()), hidden=8, layers=1)
    fb = policy.feedback
    with torch.no_grad():
        fb.x_in.weight.zero_()
        fb.x_in.bias.zero_()
        fb.m_in.parametrizations.weight.original.copy_(5.0 * torch.eye(8, 2))
        fb.out.parametrizations.weight.original.copy_(5.0 * torch.eye(1, 8))


def test_feedback_bound_is_reached_by_aligned_weights_and_not_passed():
    """One tanh layer, no reference context, raw weights 5 e1 e1^T and 5 e1^T: unbounded, the gain at m = 0 would
    be 25 L; bounded it is exactly L there, and below L elsewhere (tanh' <= 1)."""
    policy, X = _policy()
    _aligned_feedback(policy)
    x = torch.as_tensor(X[:64], dtype=torch.float32)
    at_zero = _gains(policy, x, torch.zeros(64, 2))
    np.testing.assert_allclose(at_zero.numpy(), FEEDBACK_LIPSCHITZ_RAD_PER_RAD, rtol=1e-6)
    away = _gains(policy, x, 0.3 * torch.randn(64, 2, generator=torch.Generator().manual_seed(2)))
    assert float(away.max()) <= FEEDBACK_LIPSCHITZ_RAD_PER_RAD + 1e-6


def test_runtime_is_the_policy_and_mirrors_the_right_knee():
    policy, X = _policy(seed=2, spread=0.5)
    runtime = runtime_corrector(policy, 9.106)
    m = np.random.default_rng(4).normal(scale=0.1, size=(20, 2))
    with torch.no_grad():
        expected = policy(torch.as_tensor(X[:20], dtype=torch.float32), torch.as_tensor(m, dtype=torch.float32))
    got = [runtime.model.command(X[i], m[i]) for i in range(20)]
    np.testing.assert_allclose(got, expected.numpy(), rtol=1e-5, atol=1e-5)
    preview = Preview(np.linspace(1.0, 1.1, 10), np.full(11, 0.5))
    mirrored = Preview(-preview.target_rad, preview.load_share)
    runtime.reset()
    for t, hall in ((1.0, 0.97), (1.01, 0.99)):
        left = runtime.command("left", t, {"hall_pos_rad": hall, "hall_vel_rad_per_s": 0.3}, 0.01, preview)
        right = runtime.command("right", -t, {"hall_pos_rad": -hall, "hall_vel_rad_per_s": -0.3}, 0.01, mirrored)
        assert right == pytest.approx(-left, abs=1e-12)
    with pytest.raises(SeadesignError, match="preview"):
        runtime.command("left", 1.0, {"hall_pos_rad": 1.0, "hall_vel_rad_per_s": 0.0}, 0.01)


@pytest.mark.parametrize("past,preview", [(5, 10), (0, 3), (4, 0)])
def test_reference_buffer_cuts_long_previews_and_reads_missing_load_as_none(past, preview):
    """The online buffer with previews longer than its window gives the rows of the exact window (the offline
    features); with no load share given, its load columns are 0."""
    rng = np.random.default_rng(past + preview)
    window = ReferenceWindow(past, preview)
    target, load = np.cumsum(rng.normal(size=40)), rng.uniform(size=40)
    offline = reference_features(target, load, 7.5, window)
    buf, bare = ReferenceBuffer(window, 7.5), ReferenceBuffer(window, 7.5)
    loads = [n for n in window.feature_names() if n.startswith("load_share")]
    cols = [window.feature_names().index(n) for n in loads]
    for t in range(40):
        ahead = target[t + 1: t + 1 + preview + 3]
        np.testing.assert_array_equal(buf.features(target[t], ahead, load[t: t + 4 + preview]), offline[t])
        np.testing.assert_array_equal(bare.features(target[t], ahead, load[:0])[cols], 0.0)


def _walk(spring: dict, trials: list[Trial]) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
    """Targets, stances (trials, steps, 2) on the ground and the reference features (trials, steps, 2, d)."""
    _, target, stance = protocol_tensors(trials)
    feats = reference_features(np.moveaxis(target.numpy(), 2, 1), np.moveaxis(stance.numpy(), 2, 1),
                               spring["k_Nm_per_rad"], WINDOW)
    return target, stance, torch.as_tensor(np.moveaxis(feats, 1, 2), dtype=torch.float32)


def test_gradient_reaches_both_branches_through_the_torch_knee(spring_dict):
    """The mean squared Hall error of a 30-sample rollout on the ground (noise on) has finite, nonzero gradients
    for the feed-forward and the feedback parameters."""
    policy, _ = _policy(seed=5, spread=0.2)
    cfg = KneeConfig.from_spring(spring_dict)
    knee = TorchKnee(cfg, knee_effects(cfg, ground=True), noise=True)
    target, stance, x = _walk(spring_dict, [Trial("front", 0.15, 2.0), Trial("back_right", 0.1, 2.0)])
    knee.reset(target[:, 0], stance[:, 0])
    with torch.no_grad():
        rollout(knee, lambda obs, k: target[:, k], stance, 120)  # into the walk
    out = rollout(knee, window_policy(policy, x, target, 120, 30, knee.dt), stance, 30)
    ((out["hall_rad"] - target[:, 120:150]) ** 2).mean().backward()
    for branch in (policy.ff, policy.feedback):
        grads = [p.grad for p in branch.parameters() if p.requires_grad]
        assert all(g is not None and torch.isfinite(g).all() for g in grads)
        assert sum(float(g.abs().sum()) for g in grads) > 0


def test_gradient_through_the_loop_matches_finite_differences(spring_dict):
    """d loss / d (feedback output weights) along a random direction, autograd against a central difference
    (float64, no noise or quantisation): the gradient includes the path through the measured Hall reading
    back into the feedback (cutting that path moves it by 1 %; measured agreement 7e-7 relative)."""
    policy, _ = _policy(seed=7, spread=0.5)
    _aligned_feedback(policy)
    policy.double()
    cfg = KneeConfig.from_spring(spring_dict)
    chain = configure_chain(knee_effects(cfg, ground=True), QUIET)
    target, stance, x = _walk(spring_dict, [Trial("front", 0.15, 2.0)])
    knee = TorchKnee(cfg, chain)
    knee.reset(target[:, 0], stance[:, 0])
    with torch.no_grad():
        rollout(knee, lambda obs, k: target[:, k], stance, 110)
    start = knee.state()
    weight = policy.feedback.m_in.parametrizations.weight.original
    direction = torch.randn(weight.shape, generator=torch.Generator().manual_seed(8), dtype=torch.float64)

    def loss() -> torch.Tensor:
        knee.load_state(start)
        out = rollout(knee, window_policy(policy, x, target, 110, 40, knee.dt), stance, 40)
        return ((out["hall_rad"] - target[:, 110:150]) ** 2).mean()

    analytic = float(torch.autograd.grad(loss(), weight)[0].flatten() @ direction.flatten())
    eps = 1e-5
    with torch.no_grad():
        weight += eps * direction
        up = float(loss())
        weight -= 2 * eps * direction
        down = float(loss())
        weight += eps * direction
    numeric = (up - down) / (2 * eps)
    assert abs(numeric) > 1e-3
    assert analytic == pytest.approx(numeric, rel=1e-5)


def test_runtime_in_the_simulator_follows_the_policy_in_the_torch_knee(spring_dict):
    """The training loop and the evaluation loop are one loop: the NumPy runtime driven by `run_closed_loop`
    (window from the preview, m from the measured channels, right knee mirrored) and the torch policy in the torch
    knee, both on the ground without noise or quantisation, give the same commands and Hall readings
    (measured max 1.1e-6 rad command, 3.0e-6 rad Hall; the twins alone agree to 5.6e-6 rad)."""
    policy, _ = _policy(seed=6, spread=0.3)
    trials = [Trial("front", 0.15, 3.0), Trial("back_right", 0.1, 3.0)]
    cfg = KneeConfig.from_spring(spring_dict)
    chain = configure_chain(knee_effects(cfg, ground=True), QUIET)
    run = run_closed_loop(runtime_corrector(policy, spring_dict["k_Nm_per_rad"]), spring_dict, trials, ground=True,
                          effects=chain)
    assert not run.unstable
    target, stance, x = _walk(spring_dict, trials)
    knee = TorchKnee(cfg, chain)
    knee.reset(target[:, 0], stance[:, 0])
    with torch.no_grad():
        out = rollout(knee, window_policy(policy, x, target, 0, target.shape[1], knee.dt), stance, target.shape[1])
    np.testing.assert_allclose(run.command * SIGN, out["command_rad"].numpy(), atol=2e-5)
    np.testing.assert_allclose(run.hall * SIGN, out["hall_rad"].numpy(), atol=2e-5)
    assert np.abs(run.command * SIGN - target.numpy()).max() > 0.05  # the policy does correct


TINY = ClosedLoopSettings(directions=("front", "back_right"), speeds=(0.15,), val_speeds=(0.075,),
                          trial_s=3.0, window_steps=50, max_epochs=3, patience=3)


def test_training_lowers_the_validation_error_and_is_seeded():
    """From scratch on two trials (hanging and ground): the validation mean |Hall error| drops below the
    starting one (measured 0.186 -> 0.030 rad in 3 epochs); the same seed gives the same curve."""
    first = train_closed_loop(thesis_spring(), TINY)
    errors = [row["val_mean_abs_error_rad"] for row in first.curve]
    assert first.best_epoch > 0 and errors[first.best_epoch] < 0.5 * errors[0]
    assert first.policy.feedback_lipschitz_bound() <= FEEDBACK_LIPSCHITZ_RAD_PER_RAD + 1e-6
    again = train_closed_loop(thesis_spring(), TINY)
    assert [r["val_mean_abs_error_rad"] for r in again.curve] == errors


def test_training_batch_runs_each_row_at_its_stiffness_and_tells_the_policy_spring_k():
    """Rows: per setting and k scale, the trials. At the static start of a hanging knee the spring holds the
    shank's weight: k x scale x (|deflection| - half the backlash) = |A sin(angle - hip flexion)| (analytic; measured
    to 1.5e-13 relative, the smoothed dead zone being flat that far out), in each k group with its own scale;
    every row's k input is spring.json's."""
    spring = thesis_spring()
    settings = dataclasses.replace(TINY, k_scales=(0.8, 1.25), noise=False)
    b = _batch(spring, settings)
    n = len(settings.trials(settings.speeds)) + len(settings.trials(settings.val_speeds))
    assert b.target.shape[0] == 2 * 2 * n  # hanging and ground x 2 scales
    b.knee.reset(b.target[:, 0], b.stance[:, 0])
    state = b.knee.state()
    cfg = KneeConfig.from_spring(spring)
    beyond = (state.motor_rad - state.angle_rad).abs().numpy() - 0.5 * cfg.backlash_rad  # (rows, 2), flexion
    gravity = np.abs(cfg.gravity_amplitude_Nm * np.sin(state.angle_rad.numpy() - cfg.hip_flexion_rad))
    for group, scale in enumerate((0.8, 1.25)):  # the hanging rows
        rows = slice(group * n, (group + 1) * n)
        np.testing.assert_allclose(cfg.k_Nm_per_rad * scale * beyond[rows], gravity[rows], rtol=1e-12)
    np.testing.assert_array_equal(b.features[..., -1].numpy(), np.float32(spring["k_Nm_per_rad"]))


def test_settings_refuse_overlapping_speeds_and_a_wrong_window():
    with pytest.raises(SeadesignError, match="disjoint"):
        ClosedLoopSettings(speeds=(0.1, 0.2), val_speeds=(0.1,))
    policy, _ = _policy()
    with pytest.raises(SeadesignError, match="reference window"):
        ClosedLoopPolicy.from_feedforward(policy.ff, ReferenceWindow(past=2, preview=3))


#: 8 epochs from scratch, fixed (so the result does not depend on the machine's speed)
SLOW = ClosedLoopSettings(max_epochs=8)


@pytest.mark.slow
def test_the_closed_loop_policy_from_scratch_meets_the_closed_loop_goal_in_every_cell():
    """The corrector trained for `SLOW` (k x0.8 / 1 / 1.25) meets the goal in all 36 cells of the thesis protocol
    (18 trials x hanging / ground) against none, PI and the k-feed-forward in the NumPy simulator, with no unstable
    or oscillating flag. Measured: smallest gain 0.880 hanging, 0.756 ground (goal 0.30); mean |Hall error| 0.0129
    rad hanging, 0.0719 rad ground; rest chatter 0.0022 rad (flag 0.02); feedback bound 0.500 rad/rad. The
    thresholds leave a few times the measured margin. (The default, fine-tuning the reference network, is held in
    every case by `test_corrector_reference.py`.)"""
    spring = thesis_spring()
    k = spring["k_Nm_per_rad"]
    res = train_closed_loop(spring, SLOW)
    corrector = runtime_corrector(res.policy, k, name="closedloop")
    runs, rows = {}, {}
    for setting in ("hanging", "ground"):
        table, runs[setting] = closed_loop_table([NoCorrection(), HallPI(), FeedForward(k), corrector], spring,
                                                 (setting,))
        rows[setting] = table.set_index("candidate").loc["closedloop"]
    goal = goal_table(runs, "closedloop")
    assert len(goal) == 36 and goal.meets_goal.all() and not goal.flagged.any()
    assert goal.gain.min() >= 0.6
    assert rows["hanging"].mean_abs_error_rad < 0.02 and rows["ground"].mean_abs_error_rad < 0.09
    assert max(r.rest_chatter_rms_max_rad for r in rows.values()) < 0.005
    assert res.policy.feedback_lipschitz_bound() <= 0.5 + 1e-6  # the stated design bound, rad/rad
