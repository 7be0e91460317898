"""Knee and bench simulators: physics against analytic references, determinism, round trip, closed loop."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from seadesign.constants import G_M_PER_S2
from seadesign.data import read_bench, read_recording, write_bench, write_recording
from seadesign.twin import (
    BenchProtocol,
    Gait,
    KneeConfig,
    KneeSession,
    Trial,
    bench_effects,
    configure_chain,
    knee_effects,
    simulate,
    simulate_bench,
    thesis_protocol,
)

QUIET = ["hall_noise=off", "hall_quantisation=off", "motor_quantisation=off", "effort_noise=off", "gear_friction=off"]


def _session(spring, *, ground=False, options=(), trials=None, gait=Gait(), seed=0, rate_hz=100.0):
    cfg = KneeConfig.from_spring(spring)
    chain = configure_chain(knee_effects(cfg, ground), list(options))
    return KneeSession(spring, trials or thesis_protocol(3.0)[:2], ground=ground, effects=chain, config=cfg,
                       gait=gait, seed=seed, rate_hz=rate_hz)


def test_static_deflection_is_load_over_k_plus_half_the_backlash(spring_dict):
    """Standing still, hanging: k (motor - link - b/2) = m g l_c sin(link - hip flexion)."""
    standing = Gait(stand_s=100.0)
    session = _session(spring_dict, options=QUIET, gait=standing, trials=[Trial("front", 0.1, 4.0)])
    df = session.run()
    cfg = session.config
    last = df.iloc[-1]
    link, motor = last["l_hall_pos"], last["l_knee_pos"]
    load = cfg.gravity_amplitude_Nm * np.sin(link - cfg.hip_flexion_rad)
    b = spring_dict["actuator"]["backlash_rad"]
    assert motor - link == pytest.approx(load / spring_dict["k_Nm_per_rad"] + b / 2, rel=1e-3)
    assert last["l_knee_eff"] == pytest.approx(load, rel=1e-3)


def test_static_deflection_under_body_weight_on_the_ground(spring_dict):
    standing = Gait(stand_s=100.0)
    session = _session(spring_dict, ground=True, options=QUIET + ["backlash=off"], gait=standing,
                       trials=[Trial("front", 0.1, 4.0)])
    last = session.run().iloc[-1]
    cfg = session.config
    link, motor = last["l_hall_pos"], last["l_knee_pos"]
    lean = np.arctan2(cfg.upper_leg_m * np.sin(link), cfg.lower_leg_m + cfg.upper_leg_m * np.cos(link))
    stance = 0.5 * cfg.stance_weight_share * cfg.mass_kg * G_M_PER_S2 * cfg.lower_leg_m * np.sin(lean)
    gravity = cfg.gravity_amplitude_Nm * np.sin(link - cfg.hip_flexion_rad)
    assert (motor - link) * spring_dict["k_Nm_per_rad"] == pytest.approx(gravity - stance, rel=1e-3)


def test_disabled_effect_leaves_no_trace(spring_dict):
    base = _session(spring_dict).run()
    cfg = KneeConfig.from_spring(spring_dict)
    without = [e for e in knee_effects(cfg) if e.name != "hysteresis"]
    from seadesign.effects import EffectChain

    session = KneeSession(spring_dict, thesis_protocol(3.0)[:2], effects=EffectChain(without), config=cfg)
    pd.testing.assert_frame_equal(base, session.run())
    with_it = _session(spring_dict, options=["hysteresis:torque_Nm=0.5"]).run()
    assert not np.allclose(with_it["l_hall_pos"], base["l_hall_pos"])


def test_seed_determinism(spring_dict):
    a, b, c = (_session(spring_dict, seed=s).run() for s in (1, 1, 2))
    pd.testing.assert_frame_equal(a, b)
    assert not a["l_hall_pos"].equals(c["l_hall_pos"])


def test_round_trip_with_metadata(tmp_path, spring_dict):
    df, meta = simulate(spring_dict, thesis_protocol(2.0)[:3], ground=True, seed=5, rate_hz=50.0)
    back = read_recording(write_recording(df, tmp_path / "sim.csv", meta))
    pd.testing.assert_frame_equal(df, back.drop(columns=[]), check_like=False)
    assert back.attrs["metadata"]["seed"] == 5 and back.attrs["metadata"]["rate_hz"] == 50.0
    declared = {e["name"]: e["enabled"] for e in back.attrs["metadata"]["effects"]}
    assert declared["ground_contact"] and declared["backlash"] and not declared["hysteresis"]
    assert np.allclose(np.diff(back["time_s"]), 0.02)
    assert (back["r_knee_pos"] < 0).all() and (back["l_knee_pos"] > 0).all()  # right knee mirrored


def test_velocity_limit_and_closed_loop_command(spring_dict):
    session = _session(spring_dict, trials=[Trial("front", 0.2, 2.0)])
    seen = []

    def controller(obs):
        seen.append(obs.row(0))
        return obs.target + np.array([0.5, -0.5])  # a big offset: the servo runs at its speed limit first

    df = session.run(controller)
    assert len(seen) == len(df) == 200
    assert np.allclose(df["l_cmd_pos"].to_numpy(), session.target[0, :, 0] + 0.5)
    w0 = spring_dict["actuator"]["no_load_speed_rad_per_s"]
    speed = df["l_knee_vel"].abs().max()
    assert 0.8 * w0 < speed <= w0  # limited by the torque-speed line, never above the no-load speed
    assert set(seen[0]) >= {"l_knee_pos", "r_hall_pos", "l_target", "time_s"}


def test_bench_dead_zone_has_the_set_width(spring_dict):
    b = 0.04
    chain = configure_chain(bench_effects(spring_dict["k_Nm_per_rad"]),
                            [f"dead_band:width_rad={b}", "hall_noise=off", "torque_noise=off"])
    df, meta = simulate_bench(spring_dict, BenchProtocol("ramp", duration_s=20.0), effects=chain)
    d, tau = df["deflection_rad"].to_numpy(), df["torque_Nm"].to_numpy()
    assert np.all(tau[np.abs(d) < b / 2] == 0)
    outside = np.abs(d) > b / 2
    np.testing.assert_allclose(tau[outside], spring_dict["k_Nm_per_rad"] * (d[outside] - np.sign(d[outside]) * b / 2))
    assert "dead_band" in meta["effects_enabled"]


def test_bench_linear_spring_and_round_trip(tmp_path, spring_dict):
    chain = configure_chain(bench_effects(spring_dict["k_Nm_per_rad"]), ["hall_noise=off", "torque_noise=off"])
    df, meta = simulate_bench(spring_dict, BenchProtocol(duration_s=20.0), effects=chain, seed=2)
    np.testing.assert_allclose(df["torque_Nm"], spring_dict["k_Nm_per_rad"] * df["deflection_rad"])
    assert df["torque_Nm"].abs().max() == pytest.approx(4.8, rel=1e-3)
    back = read_bench(write_bench(df, tmp_path / "bench.csv", meta))
    pd.testing.assert_frame_equal(df, back)
    assert back.attrs["metadata"]["protocol"]["profile"] == "sine"


def _tanh_spring(spring: dict, end_Nm: float, hard_stop: bool = False) -> dict:
    """spring.json whose torque curve is T = A tanh(theta / B), A = 6 Nm, A / B = k, sampled to `end_Nm`."""
    a, b = 6.0, 6.0 / spring["k_Nm_per_rad"]
    theta = np.linspace(0.0, b * np.arctanh(end_Nm / a), 31)
    curve = {"rotation_rad": list(theta), "torque_Nm": list(a * np.tanh(theta / b)), "source": "test",
             "stop_reason": "contact", "hard_stop": hard_stop}
    return {**spring, "schema_version": 2, "torque_curve": curve}


def test_bench_uses_the_torque_curve_and_never_extrapolates(spring_dict):
    """With a curve in spring.json the bench drives the rotation that carries the torque amplitude and the
    torque follows the curve (closed form B atanh / A tanh); an amplitude past the curve's end is refused,
    unless the curve ends at a hard stop."""
    from seadesign.design.spring import torque_curve
    from seadesign.effects import CurveRangeError

    spring = _tanh_spring(spring_dict, end_Nm=5.0)
    a, b = 6.0, 6.0 / spring["k_Nm_per_rad"]
    chain = configure_chain(bench_effects(spring["k_Nm_per_rad"], torque_curve(spring)),
                            ["hall_noise=off", "torque_noise=off"])
    df, _ = simulate_bench(spring, BenchProtocol(torque_amplitude_Nm=4.8, duration_s=20.0), effects=chain)
    d = df["deflection_rad"].to_numpy()
    assert np.abs(d).max() == pytest.approx(b * np.arctanh(4.8 / a), rel=1e-6)  # the sine's peak: measured 2.6e-7
    # PCHIP through 31 points vs the closed form: measured 4.9e-5 Nm at most
    np.testing.assert_allclose(df["torque_Nm"], a * np.tanh(d / b), atol=1.5e-4)
    with pytest.raises(CurveRangeError, match="past the spring's torque curve"):
        simulate_bench(spring, BenchProtocol(torque_amplitude_Nm=5.5, duration_s=20.0), effects=chain)
    stop = _tanh_spring(spring_dict, end_Nm=5.0, hard_stop=True)
    df, _ = simulate_bench(stop, BenchProtocol(torque_amplitude_Nm=5.5, duration_s=20.0))
    assert df["deflection_rad"].abs().max() <= b * np.arctanh(5.0 / a) + 0.01  # held at the stop (+ noise)


def test_partial_recording_is_the_full_runs_prefix(spring_dict):
    """Stopped at sample m, the recording holds each trial's first m rows of the full run (same seed and
    commands), at the full run's times; the command's rate at the cut is the only one-sided column."""
    full = _session(spring_dict, seed=4).run()
    part = _session(spring_dict, seed=4)
    with pytest.raises(Exception, match="partial"):
        part.recording()
    m = 57
    for _ in range(m):
        part.step()
    got = part.recording(partial=True)
    n_steps = len(full) // 2
    prefix = pd.concat([full.iloc[:m], full.iloc[n_steps:n_steps + m]], ignore_index=True)
    assert len(got) == 2 * m and part.n_logged == m
    same = [c for c in full.columns if not c.endswith(("_cmd_vel", "_cmd_acc"))]
    pd.testing.assert_frame_equal(got[same], prefix[same])
    assert np.allclose(got["l_cmd_vel"].to_numpy()[: m - 2], prefix["l_cmd_vel"].to_numpy()[: m - 2])


def test_the_simulators_speak_the_one_signal_vocabulary():
    from seadesign.effects import SIGNALS
    from seadesign.twin import KneeConfig, bench_effects, knee_effects

    cfg = KneeConfig(k_Nm_per_rad=9.0, stall_torque_Nm=11.7, no_load_speed_rad_per_s=4.8, backlash_rad=0.004,
                     mass_kg=8.0, lower_leg_m=0.2, upper_leg_m=0.2)
    for chain in (knee_effects(cfg), bench_effects(9.0)):
        for e in chain:
            used = [e.signal(r) for r in e.reads] + [e.target()]
            assert set(used) <= set(SIGNALS), (e.name, set(used) - set(SIGNALS))
