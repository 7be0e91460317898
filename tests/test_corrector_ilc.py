"""ILC labels and the reference window: the learning operator inverts the linear knee, the iteration
converges in the simulator and its commands replay, the online window equals the offline one."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import thesis_spring
from scipy.signal import lsim

from seadesign.corrector.ilc import NOISE_EFFECTS, ILCSettings, LinearKnee, inverse_command, learn_commands
from seadesign.corrector.imitation import ImitationSettings, ilc_labels
from seadesign.corrector.reference import ReferenceBuffer, ReferenceWindow, reference_features
from seadesign.errors import SeadesignError
from seadesign.twin import KneeConfig, KneeSession, Trial, knee_effects
from seadesign.twin.knee import SIGN


def test_inverse_command_drives_the_linear_knee_along_the_wanted_path():
    """The linear knee as a transfer function (written here from its ODEs), driven by inverse_command(theta),
    follows theta: servo qm' = a (Kp (c - qm) - k (qm - th)), link J th'' = k (qm - th) - b th'."""
    knee = LinearKnee(k_Nm_per_rad=9.0, inertia_kg_m2=0.016, viscous_Nm_s_per_rad=0.15, p_gain_Nm_per_rad=60.0,
                      speed_per_torque_rad_per_s_Nm=0.41)
    k, J, b, kp, a = 9.0, 0.016, 0.15, 60.0, 0.41
    # th/c: qm (s + a Kp + a k) = a Kp c + a k th;  th (J s^2 + b s + k) = k qm
    num = [a * kp * k]
    den = np.polyadd(np.polymul([1.0, a * (kp + k)], [J, b, k]), [-a * k * k])
    errors = []
    for dt in (1e-3, 5e-4):
        t = np.arange(0.0, 2.0, dt)
        theta = 0.3 * np.sin(2 * np.pi * 1.5 * t) ** 3  # starts at rest
        _, th, _ = lsim((num, den), inverse_command(theta[None, :], dt, knee)[0], t)
        errors.append(np.abs(th - theta).max())
    # measured 7.2e-4 and 3.5e-4 rad: the finite differences' first-order error, halving with dt
    assert errors[0] < 1e-3 and 0.4 < errors[1] / errors[0] < 0.6
    _, th_plain, _ = lsim((num, den), theta, t)  # without the inverse: the knee lags visibly
    assert np.abs(th_plain - theta).max() > 50 * errors[1]


@pytest.fixture(scope="module")
def short_batch():
    spring = thesis_spring()
    trials = [Trial("front", 0.1, 4.0), Trial("back_right", 0.2, 4.0)]
    return spring, trials, learn_commands(spring, trials, ground=False)


def test_ilc_converges_and_its_commands_replay(short_batch):
    """The iteration reaches its plateau, cuts the Hall error > 10x, stays within its bound, and the
    learned command replayed in a fresh simulator (noise off) gives the error it reported."""
    spring, trials, res = short_batch
    assert res.converged
    errors = res.mean_abs_error_rad
    assert errors[res.best_iteration] == min(errors) and errors[res.best_iteration] < errors[0] / 10
    assert np.abs(res.correction_rad).max() <= ILCSettings().max_correction_rad + 1e-12
    chain = knee_effects(KneeConfig.from_spring(spring), False)
    for name in NOISE_EFFECTS:
        chain = chain.configure(name, enabled=False)
    session = KneeSession(spring, trials, effects=chain)
    hall = np.empty_like(res.command_rad)
    obs, t = session.observe(), 0
    while obs is not None:
        hall[:, t] = obs.hall_pos * SIGN
        obs = session.step(res.command_rad[:, t] * SIGN)
        t += 1
    assert np.mean(np.abs(res.target_rad - hall)) == pytest.approx(errors[res.best_iteration], rel=1e-12)


def test_ilc_keeps_the_correction_inside_its_bound_on_both_sides():
    """With a bound the knee's dynamics need more than (0.05 rad), the correction reaches it both ways and
    never passes it."""
    res = learn_commands(thesis_spring(), [Trial("front", 0.2, 3.0)], settings=ILCSettings(max_correction_rad=0.05))
    assert res.correction_rad.max() == pytest.approx(0.05, abs=1e-12)
    assert res.correction_rad.min() == pytest.approx(-0.05, abs=1e-12)


def test_ilc_that_stops_before_its_plateau_is_not_a_label(spring_dict):
    settings = ImitationSettings(speeds=(0.1,), conditions=("hanging",), k_scales=(1.0,), trial_s=3.0,
                                 ilc=ILCSettings(max_iterations=2))
    with pytest.raises(SeadesignError, match="did not reach its plateau"):
        ilc_labels(spring_dict, settings)


def test_online_reference_window_equals_the_offline_features():
    """ReferenceBuffer fed step by step with the preview (truncated at the trial's end) gives the rows of
    reference_features, ends included."""
    rng = np.random.default_rng(3)
    n, window = 40, ReferenceWindow(past=4, preview=6)
    target, load = np.cumsum(rng.normal(size=n)), rng.uniform(size=n)
    offline = reference_features(target, load, 7.5, window)
    buf = ReferenceBuffer(window, 7.5)
    for t in range(n):
        row = buf.features(target[t], target[t + 1: t + 1 + window.preview], load[t: t + 1 + window.preview])
        np.testing.assert_array_equal(row, offline[t])
    assert offline.shape[1] == len(window.feature_names())
