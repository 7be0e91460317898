"""The differentiable torch knee against the NumPy knee simulator, its gradients, windows and refusals."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import torch

from seadesign.design.spring import CurveRangeError
from seadesign.effects import EffectChain, TemperatureSoftening
from seadesign.errors import ConfigError
from seadesign.twin import Gait, KneeConfig, KneeSession, Trial, configure_chain, knee_effects, thesis_protocol
from seadesign.twin.knee import SIGN
from seadesign.twin.torch_knee import TorchKnee, protocol_tensors, rollout, to_robot

QUIET = ["hall_noise=off", "hall_quantisation=off", "motor_quantisation=off", "effort_noise=off"]
#: Agreement on the thesis protocol (18 trials x 10 s, both settings), set at about 3x the largest error
#: measured over all cases below (max: Hall 5.6e-6 rad, motor 1.4e-6 rad, effort 1.3e-3 Nm, motor velocity
#: 3.4e-4 rad/s, Hall velocity 3.2e-4 rad/s; mean: Hall 1.8e-7 rad, motor 2.7e-8 rad, effort 3.3e-6 Nm, motor
#: velocity 1.2e-6 rad/s, Hall velocity 4.8e-6 rad/s). The dead zone's smoothing (1e-4 rad) sets them.
MAX_ERROR = {"hall": 2e-5, "motor": 5e-6, "effort": 4e-3, "velocity": 1e-3, "hall_velocity": 1e-3}
MEAN_ERROR = {"hall": 6e-7, "motor": 1e-7, "effort": 1e-5, "velocity": 4e-6, "hall_velocity": 1.5e-5}


pytestmark = pytest.mark.usefixtures("one_torch_thread")


def _softening(spring: dict, a_Nm: float = 6.0) -> dict:
    """spring.json with a large-deflection curve T = A tanh(theta / B), A / B = k, to 3 B (ground loads fit)."""
    b = a_Nm / spring["k_Nm_per_rad"]
    theta = np.linspace(0.0, 3 * b, 41)
    curve = {"rotation_rad": list(theta), "torque_Nm": list(a_Nm * np.tanh(theta / b)), "source": "test",
             "stop_reason": "target_reached", "hard_stop": False}
    return {**spring, "schema_version": 2, "torque_curve": curve}


def _session(spring: dict, ground: bool, options=(), config=None, trials=None, gait=Gait()) -> KneeSession:
    """A quiet session (no noise or quantisation) with effect `options` and KneeConfig overrides `config`."""
    cfg = dataclasses.replace(KneeConfig.from_spring(spring), **(config or {}))
    chain = configure_chain(knee_effects(cfg, ground), QUIET + list(options))
    return KneeSession(spring, trials or thesis_protocol(10.0), ground=ground, effects=chain, config=cfg, gait=gait)


def _pi(session: KneeSession):
    """A PI controller on the Hall error (robot convention), as the corrector's HallPI, over the batch."""
    integral = np.zeros((session.n_trials, 2))

    def control(obs):
        e = obs.target - obs.hall_pos
        integral[:] += e * session.dt
        return obs.target + 0.2 * e + 0.1 * integral
    return control


def _record(session: KneeSession, controller=None) -> dict[str, np.ndarray]:
    """Run the session; each sample's observation and the command sent, flexion frame, (n_trials, n_steps, 2)."""
    rows = []
    obs = session.observe()
    while obs is not None:
        command = obs.target if controller is None else controller(obs)
        rows.append({"hall": obs.hall_pos, "motor": obs.knee_pos, "effort": obs.knee_eff, "velocity": obs.knee_vel,
                     "hall_velocity": obs.hall_vel, "command": command})
        obs = session.step(command)
    return {f: np.stack([r[f] for r in rows], axis=1) * SIGN for f in rows[0]}


def _replay(knee: TorchKnee, session: KneeSession, command: np.ndarray) -> dict[str, np.ndarray]:
    """The torch knee driven by the recorded commands over the session's protocol."""
    stance = torch.as_tensor(session.stance)
    knee.reset(session.target[:, 0] * SIGN, stance[:, 0])
    cmd = torch.as_tensor(command)
    with torch.no_grad():
        out = rollout(knee, lambda obs, k: cmd[:, k], stance, session.n_steps)
    return {"hall": out["hall_rad"].numpy(), "motor": out["motor_rad"].numpy(), "effort": out["effort_Nm"].numpy(),
            "velocity": out["motor_velocity_rad_per_s"].numpy(), "hall_velocity": out["hall_velocity_rad_per_s"].numpy()}


def _errors(spring: dict, ground: bool, options=(), config=None, pi: bool = False, k_factor: float = 1.0) -> dict:
    """Max and mean |torch - simulator| per observed channel; `k_factor` scales spring.json's k."""
    session = _session({**spring, "k_Nm_per_rad": k_factor * spring["k_Nm_per_rad"]}, ground, options, config)
    ref = _record(session, _pi(session) if pi else None)
    got = _replay(TorchKnee.from_session(session), session, ref["command"])
    return {f: (float(np.abs(got[f] - ref[f]).max()), float(np.abs(got[f] - ref[f]).mean())) for f in MAX_ERROR}


def _assert_agrees(errors: dict) -> None:
    for f, (worst, mean) in errors.items():
        assert worst < MAX_ERROR[f], f"{f}: max error {worst:.3g} (tolerance {MAX_ERROR[f]:g}); all: {errors}"
        assert mean < MEAN_ERROR[f], f"{f}: mean error {mean:.3g} (tolerance {MEAN_ERROR[f]:g}); all: {errors}"


CASES = {
    "relayed_target": {},
    "pi_controller": {"pi": True},
    "k_x0.7": {"k_factor": 0.7},
    "other_parameters": {"config": {"p_gain_Nm_per_rad": 40.0, "torque_limit_Nm": 6.0, "max_substep_s": 0.001,
                                    "lower_leg_mass_fraction": 0.1, "hip_flexion_rad": 0.3},
                         "options": ["backlash:width_rad=0.01", "friction:coulomb_Nm=0.1,viscous_Nm_s_per_rad=0.3",
                                     "ground_contact:weight_N=30", "gear_friction:coulomb_Nm=0.5"]},
    "stiffness_scale_x1.4": {"options": ["stiffness_scale:scale=1.4"]},
    "viscoelastic": {"options": ["viscoelastic"]},
    "hysteresis": {"options": ["hysteresis"]},
    "hall_delay_2.5_samples": {"options": ["hall_delay:delay_s=0.025"]},
    "effort_lag": {"options": ["effort_lag"]},
}
OTHER_CASES = {
    "thermal_softening": {"options": ["thermal_softening:softening_per_J=0.002"]},  # stronger: the leg buckles
    "cubic_stiffening": {"options": ["cubic_stiffening"]},
    "dead_band": {"options": ["dead_band"]},
    "sensor_offset_step_drift_wrap": {"options": ["hall_offset", "hall_step:time_s=3", "hall_drift", "hall_wrap"]},
}


@pytest.mark.parametrize("ground", [False, True], ids=["hanging", "ground"])
@pytest.mark.parametrize("case", list(CASES))
def test_matches_the_knee_simulator_on_the_thesis_protocol(spring_dict, case, ground):
    _assert_agrees(_errors(spring_dict, ground, **CASES[case]))


@pytest.mark.parametrize("ground", [False, True], ids=["hanging", "ground"])
def test_matches_with_the_large_deflection_curve(spring_dict, ground):
    _assert_agrees(_errors(_softening(spring_dict), ground))


@pytest.mark.parametrize("case", list(OTHER_CASES))
def test_matches_with_the_other_effects_on_the_ground(spring_dict, case):
    """The rest of the chain's optional effects, on the ground only (the hanging runs agree as closely)."""
    _assert_agrees(_errors(spring_dict, True, **OTHER_CASES[case]))


def test_matches_through_the_torque_and_speed_limits(spring_dict):
    """Command steps of 0.8 rad while standing: the servo runs into its torque limit and (stepping against the
    spring's torque) its speed limit; the hard clamps agree with the simulator's."""
    session = _session(spring_dict, False, trials=[Trial("front", 0.0, 3.0)] * 2, gait=Gait(stand_s=100.0))
    steps = np.where((session.time >= 0.5) & (session.time < 1.5), -0.8, 0.0) + np.where(session.time >= 2.0, 0.8, 0.0)
    step_up = np.array([[1.0], [0.5]])  # one trial steps further than the other

    def stepping(obs):
        return obs.target + step_up * steps[obs.step] * SIGN
    ref = _record(session, stepping)
    cfg = session.config
    assert np.isclose(np.abs(ref["velocity"]).max(), cfg.no_load_speed_rad_per_s)  # the speed limit acts
    got = _replay(TorchKnee.from_session(session), session, ref["command"])
    for f in MAX_ERROR:
        assert np.abs(got[f] - ref[f]).max() < MAX_ERROR[f], f


def test_a_rotation_past_the_curve_is_refused_as_in_the_simulator(spring_dict):
    """Body weight on a curve that ends at 0.8 Nm: both refuse at the start (CurveRangeError, not extrapolated)."""
    spring = _softening(spring_dict, a_Nm=0.8)
    cfg = KneeConfig.from_spring(spring)
    chain = configure_chain(knee_effects(cfg, ground=True), QUIET)
    trials = [Trial("front", 0.2, 2.0)]
    with pytest.raises(CurveRangeError, match="past the spring's torque curve"):
        KneeSession(spring, trials, ground=True, effects=chain, config=cfg)
    _, target, stance = protocol_tensors(trials)
    with pytest.raises(CurveRangeError, match="past the spring's torque curve"):
        TorchKnee(cfg, chain).reset(target[:, 0], stance[:, 0])


def _short_rollout(knee: TorchKnee, target: torch.Tensor, stance: torch.Tensor, command: torch.Tensor) -> torch.Tensor:
    knee.reset(target[:, 0], stance[:, 0])
    out = rollout(knee, lambda obs, k: command[:, k], stance, command.shape[1])
    return torch.cat([out["hall_rad"], out["effort_Nm"], out["motor_rad"]], dim=1)


@pytest.mark.parametrize("options", [[], ["viscoelastic", "hysteresis", "hall_delay:delay_s=0.015", "effort_lag"]],
                         ids=["default", "robustness_effects"])
def test_gradcheck_of_a_short_rollout(spring_dict, options):
    """Exact gradients (float64) w.r.t. the commands and w.r.t. a loaded state's link angle and velocity."""
    session = _session(spring_dict, True, options, trials=thesis_protocol(2.0)[8:10])
    knee = TorchKnee.from_session(session)
    _, target, stance = protocol_tensors(session.trials)
    start = 118  # walking, and no deflection reversal (the Dahl loop's kink) within 1e-5 rad of the window
    command = (target[:, start:start + 4] + 0.01).clone().requires_grad_(True)
    window_target, window_stance = target[:, start:], stance[:, start:]
    assert torch.autograd.gradcheck(lambda c: _short_rollout(knee, window_target, window_stance, c), (command,))

    knee.reset(target[:, 0], stance[:, 0])
    rollout(knee, lambda obs, k: target[:, k], stance, start)
    saved = knee.state()

    def from_state(angle, vel):
        knee.load_state(dataclasses.replace(saved, angle_rad=angle, velocity_rad_per_s=vel))
        out = rollout(knee, lambda obs, k: target[:, k], stance, 4)
        return torch.cat([out["hall_rad"], out["effort_Nm"]], dim=1)
    assert torch.autograd.gradcheck(from_state, (saved.angle_rad.clone().requires_grad_(True),
                                                 saved.velocity_rad_per_s.clone().requires_grad_(True)))


def test_gradients_of_a_full_rollout_are_finite_and_exact(spring_dict):
    """10 s of the protocol on the ground, corrector = a learnable command offset per trial and knee: the
    gradient is finite everywhere and matches a central difference of the loss."""
    session = _session(spring_dict, True)
    knee = TorchKnee.from_session(session)
    _, target, stance = protocol_tensors(session.trials)

    def loss(offset: torch.Tensor) -> torch.Tensor:
        knee.reset(target[:, 0], stance[:, 0])
        out = rollout(knee, lambda obs, k: target[:, k] + offset, stance, target.shape[1])
        return ((out["hall_rad"] - target) ** 2).mean()
    offset = torch.zeros(target.shape[0], 2, dtype=torch.float64, requires_grad=True)
    loss(offset).backward()
    assert torch.isfinite(offset.grad).all() and (offset.grad != 0).all()
    h = torch.zeros_like(offset)
    h[3, 1] = 1e-6
    with torch.no_grad():
        central = (loss(h) - loss(-h)) / 2e-6
    assert offset.grad[3, 1].item() == pytest.approx(central.item(), rel=1e-5)


def test_a_window_from_a_saved_state_continues_the_full_rollout(spring_dict):
    """state() at sample 200 then load_state gives the full run's samples 200..299 exactly; the window's
    gradient stops at the detached start."""
    session = _session(spring_dict, True, ["hysteresis", "hall_delay:delay_s=0.025", "effort_lag", "hall_noise=on",
                                           "effort_noise=on"],
                       trials=thesis_protocol(4.0)[:4])
    knee = TorchKnee.from_session(session, noise=True, seed=3)
    _, target, stance = protocol_tensors(session.trials)
    knee.reset(target[:, 0], stance[:, 0])
    with torch.no_grad():
        rollout(knee, lambda obs, k: target[:, k], stance, 200)
        saved = knee.state()
        full = rollout(knee, lambda obs, k: target[:, k], stance, 100)
    offset = torch.zeros(2, dtype=torch.float64, requires_grad=True)
    knee.load_state(saved)
    window = rollout(knee, lambda obs, k: target[:, k] + offset, stance, 100)
    for f in full:
        assert torch.equal(window[f].detach(), full[f]), f
    assert knee.observe().hall_rad.shape == (4, 2)
    ((window["hall_rad"] - target[:, 200:300]) ** 2).mean().backward()
    assert torch.isfinite(offset.grad).all() and offset.grad.abs().min() > 0
    assert all(not t.requires_grad for t in (saved.motor_rad, saved.angle_rad, saved.effects["hysteresis"]["z"]))


def test_noise_has_the_chains_std_and_quantisation_is_straight_through(spring_dict):
    cfg = KneeConfig.from_spring(spring_dict)
    chain = knee_effects(cfg)
    trials = [Trial("front", 0.1, 3.0)] * 4
    _, target, _ = protocol_tensors(trials)
    runs = {}
    for noise in (False, True):
        knee = TorchKnee(cfg, chain.configure("hall_quantisation", enabled=False), noise=noise, seed=1)
        knee.reset(target[:, 0])
        runs[noise] = rollout(knee, lambda obs, k: target[:, k], None, 300)["hall_rad"]
    residual = runs[True] - runs[False]
    assert residual.std().item() == pytest.approx(chain["hall_noise"].values["std_rad"], rel=0.1)

    knee = TorchKnee(cfg, chain, quantise=True)
    command = target[:, :50].clone().requires_grad_(True)
    knee.reset(target[:, 0])
    hall = rollout(knee, lambda obs, k: command[:, k], None, 50)["hall_rad"]
    q = 2 * np.pi / 2 ** chain["hall_quantisation"].values["bits"]
    steps = hall.detach() / q
    assert torch.allclose(steps, steps.round(), atol=1e-9)
    hall.sum().backward()
    assert command.grad.abs().sum() > 0


def test_float32_tracks_float64(spring_dict):
    session = _session(spring_dict, True, trials=thesis_protocol(3.0))
    _, target, stance = protocol_tensors(session.trials)
    halls = []
    for dtype in (torch.float64, torch.float32):
        knee = TorchKnee.from_session(session, dtype=dtype)
        knee.reset(target[:, 0], stance[:, 0])
        with torch.no_grad():
            halls.append(rollout(knee, lambda obs, k: target[:, k].to(dtype), stance, 300)["hall_rad"].double())
    assert halls[1].dtype == torch.float64 and (halls[0] - halls[1]).abs().max() < 1e-4


def test_refuses_what_it_cannot_represent(spring_dict):
    cfg = KneeConfig.from_spring(spring_dict)
    chain = EffectChain([*knee_effects(cfg), TemperatureSoftening("warm_spring")])
    with pytest.raises(ConfigError, match="warm_spring"):
        TorchKnee(cfg, chain)
    knee = TorchKnee(cfg, knee_effects(cfg, ground=True))
    with pytest.raises(ConfigError, match="stance"):
        knee.reset(torch.ones(1, 2))
    with pytest.raises(ConfigError, match="reset"):
        TorchKnee(cfg, knee_effects(cfg)).step(torch.ones(1, 2))


def test_robot_frame_mirrors_the_right_knee():
    x = torch.tensor([[0.3, 0.4]], dtype=torch.float64)
    assert torch.equal(to_robot(x), torch.tensor([[0.3, -0.4]], dtype=torch.float64))
    assert torch.equal(to_robot(to_robot(x)), x)


def test_stiffness_scale_varies_across_the_batch_as_one_session_per_scale(spring_dict):
    """One torch knee whose trials carry stiffness scales 0.8 / 1 / 1.25 (`vary`) gives each trial what a KneeSession
    with that scale gives (to the tolerances above); other values and absent effects are refused by name."""
    trials = [Trial("front", 0.15, 3.0), Trial("back_right", 0.1, 3.0)]
    scales = (0.8, 1.0, 1.25)
    sessions = [_session(spring_dict, True, [f"stiffness_scale:scale={s}"], trials=trials) for s in scales]
    refs = [_record(s) for s in sessions]
    cfg = KneeConfig.from_spring(spring_dict)
    chain = configure_chain(knee_effects(cfg, True), QUIET + ["stiffness_scale"])
    knee = TorchKnee(cfg, chain)
    knee.vary("stiffness_scale", scale=torch.tensor(scales).repeat_interleave(len(trials))[:, None])
    stance = torch.as_tensor(np.concatenate([s.stance for s in sessions]))
    command = torch.as_tensor(np.concatenate([r["command"] for r in refs]))
    knee.reset(command[:, 0], stance[:, 0])
    with torch.no_grad():
        hall = rollout(knee, lambda obs, k: command[:, k], stance, command.shape[1])["hall_rad"].numpy()
    expected = np.concatenate([r["hall"] for r in refs])
    assert np.abs(hall - expected).max() < MAX_ERROR["hall"]
    assert np.abs(expected[:2] - expected[4:]).max() > 0.01  # the scales do differ
    with pytest.raises(ConfigError, match="cannot vary \\['k_Nm_per_rad'\\]"):
        knee.vary("stiffness_scale", k_Nm_per_rad=torch.ones(1))
    with pytest.raises(ConfigError, match="no enabled effect 'viscoelastic'"):
        knee.vary("viscoelastic", maxwell_stiffness_Nm_per_rad=torch.ones(1))
