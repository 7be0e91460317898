"""Closed loop in the knee simulator: feed-forward cancels a linear spring, instability is caught."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from seadesign.corrector.closedloop import closed_loop_table, run_closed_loop
from seadesign.corrector.runtime import FeedForward, HallPI, NoCorrection
from seadesign.twin import Gait, KneeConfig, Trial, knee_effects

STATIC = Gait(stand_rad=1.0, walk_base_rad=1.0, lift_rad=0.0, stance_flex_per_speed=0.0)


def _spring_only(spring: dict):
    """Linear spring, gravity and viscous link damping; no backlash, friction steps or sensor effects."""
    chain = knee_effects(KneeConfig.from_spring(spring))
    for name in ("backlash", "gear_friction", "hall_noise", "hall_quantisation", "motor_quantisation", "effort_noise"):
        chain = chain.configure(name, enabled=False)
    return chain.configure("friction", coulomb_Nm=0.0, viscous_Nm_s_per_rad=0.3)


def test_feedforward_cancels_linear_spring_deflection(spring_dict):
    """At rest the servo's P law gives qm = command - tau / Kp and the spring hall = qm - tau / k.
    Without correction the Hall error is -(tau/k + tau/Kp); with command = target + tau/k it must be
    exactly -tau/Kp: the spring's whole deflection is cancelled, only the servo's own error is left."""
    kp = KneeConfig.from_spring(spring_dict).p_gain_Nm_per_rad
    k = spring_dict["k_Nm_per_rad"]
    trial = [Trial("front", 0.0, 3.0)]
    none = run_closed_loop(NoCorrection(), spring_dict, trial, effects=_spring_only(spring_dict), gait=STATIC)
    ff = run_closed_loop(FeedForward(k), spring_dict, trial, effects=_spring_only(spring_dict), gait=STATIC)
    for run, expected in ((none, lambda tau: -(tau / k + tau / kp)), (ff, lambda tau: -tau / kp)):
        assert not run.unstable and not run.oscillating
        flex = run.hall[0, -1] * [1, -1] - run.target[0, -1] * [1, -1]  # knee flexion convention
        tau = run.effort[0, -1] * [1, -1]
        np.testing.assert_allclose(flex, expected(tau), atol=1e-6)
    assert abs(ff.hall[0, -1, 0] - ff.target[0, -1, 0]) < 0.2 * abs(none.hall[0, -1, 0] - none.target[0, -1, 0])


def test_closed_loop_flags_unstable_and_oscillating_controllers(spring_dict):
    trials = [Trial("front", 0.1, 2.5), Trial("back_right", 0.2, 2.5)]
    table, runs = closed_loop_table(
        [NoCorrection(), HallPI(), HallPI(kp=-1.5, ki=0.0, name="positive_feedback"),
         HallPI(kp=3.0, ki=5.0, name="high_gain")], spring_dict, ("hanging",), trials)
    flags = table.set_index("candidate")
    assert not flags.loc["none", "unstable_flag"] and not flags.loc["none", "oscillating_flag"]
    assert not flags.loc["pi", "unstable_flag"] and not flags.loc["pi", "oscillating_flag"]
    assert flags.loc["positive_feedback", "unstable_flag"]
    assert flags.loc["high_gain", "unstable_flag"] or flags.loc["high_gain", "oscillating_flag"]
    assert {"mean_abs_error_rad", "worst_trial", "best_trial", "peak_abs_error_rad"} <= set(table.columns)


def test_closed_loop_refuses_unknown_setting(spring_dict):
    from seadesign.errors import SeadesignError

    with pytest.raises(SeadesignError, match="hanging or ground"):
        closed_loop_table([NoCorrection()], spring_dict, ("upside_down",), [Trial("front", 0.1, 1.0)])


def test_unstable_run_keeps_the_samples_before_the_stop(spring_dict):
    """A run stopped for instability still yields the robot-format rows it ran, usable as training data."""
    from seadesign.corrector.recordings import recording_from_table

    trials = [Trial("front", 0.1, 2.5), Trial("back_right", 0.2, 2.5)]
    run = run_closed_loop(HallPI(kp=-1.5, ki=0.0, name="positive_feedback"), spring_dict, trials)
    assert run.unstable
    logged = int(np.isfinite(run.command[0, :, 0]).sum()) - 1  # the last command was refused, not sent
    assert run.recording is not None and len(run.recording) == 2 * logged < 2 * 250
    np.testing.assert_allclose(run.recording["l_hall_pos"].to_numpy()[:logged], run.hall[0, :logged, 0])
    rec, _ = recording_from_table(run.recording, "unstable")
    assert len(rec.time_s) > 0 and len(np.unique(rec.segment)) >= 2  # the two trials never pair across


def test_iterate_adds_each_rounds_run_to_the_pool(spring_dict):
    """Round r trains on the start run plus the runs of rounds < r: the pool and the samples grow by
    the previous round's recording, and every round is scored in closed loop."""
    from seadesign.corrector.dataset import DatasetSpec
    from seadesign.corrector.iterative import iterate
    from seadesign.corrector.train import TrainConfig

    trials = [Trial("front", 0.1, 2.0), Trial("rotate_right", 0.2, 2.0)]
    cfg = TrainConfig(model="mlp", max_epochs=30, patience=10, batch_size=256, seed=3)
    spec = DatasetSpec(task="command", modalities="velocity_effort", positive=True)
    table, results = iterate(spring_dict, [], spec, cfg, rounds=2, trials=trials, seed=1)
    assert list(table["round"]) == [0, 1, 2] and len(results) == 3
    assert list(table["n_recordings"]) == [1, 2, 3]
    grown = np.diff(table["n_samples"].to_numpy())
    assert np.all(grown > 0)
    recorded = table["recorded_s"].to_numpy()
    stable = ~table["unstable_flag"].to_numpy(bool)
    np.testing.assert_allclose(recorded[stable], 2 * 2.0)  # a completed run records both trials in full
    assert np.isfinite(table["mean_abs_error_rad"]).all()
    again, _ = iterate(spring_dict, [], spec, cfg, rounds=2, trials=trials, seed=1)
    pd.testing.assert_frame_equal(table, again)  # seeded: the same rounds, numbers and flags


def _softening(spring: dict) -> dict:
    """spring.json with a large-deflection curve T = A tanh(theta / B) of the same small-load k (A / B = k),
    A = 0.8 Nm: at the static knee's 0.45 Nm the deflection is 13 % above effort / k."""
    a, b = 0.8, 0.8 / spring["k_Nm_per_rad"]
    theta = np.linspace(0.0, 4 * b, 41)
    curve = {"rotation_rad": list(theta), "torque_Nm": list(a * np.tanh(theta / b)), "source": "test",
             "stop_reason": "target_reached", "hard_stop": False}
    return {**spring, "schema_version": 2, "torque_curve": curve}


def test_feedforward_with_the_torque_curve_cancels_a_softening_spring(spring_dict):
    """As above with the curve as the spring's law: command = target + theta(tau) leaves -tau/Kp; effort / k
    leaves the curve's extra deflection theta(tau) - tau / k, with theta = B atanh(tau / A) in closed form."""
    from seadesign.design.spring import torque_curve

    spring = _softening(spring_dict)
    kp = KneeConfig.from_spring(spring).p_gain_Nm_per_rad
    k, a, b = spring["k_Nm_per_rad"], 0.8, 0.8 / spring["k_Nm_per_rad"]
    trial = [Trial("front", 0.0, 3.0)]
    curve_ff = run_closed_loop(FeedForward(k, torque_curve(spring)), spring, trial, effects=_spring_only(spring),
                               gait=STATIC)
    k_ff = run_closed_loop(FeedForward(k), spring, trial, effects=_spring_only(spring), gait=STATIC)
    for run, expected in ((curve_ff, lambda tau: -tau / kp),
                          (k_ff, lambda tau: -(b * np.arctanh(tau / a) - tau / k) - tau / kp)):
        assert not run.unstable and not run.oscillating
        flex = run.hall[0, -1] * [1, -1] - run.target[0, -1] * [1, -1]
        tau = run.effort[0, -1] * [1, -1]
        assert np.all(np.abs(tau) > 0.4)  # loaded where the curve bends
        np.testing.assert_allclose(flex, expected(tau), atol=1e-5)  # measured 2e-9 (curve), 2.6e-6 (k: PCHIP vs atanh)
