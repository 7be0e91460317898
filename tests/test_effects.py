"""Effect library: analytic forward models, stepping equals vectorised apply, bounds, chains."""

from __future__ import annotations

import numpy as np
import pytest

from seadesign.effects import (
    LIBRARY,
    AngleWrap,
    DahlHysteresis,
    DeadBand,
    EffectChain,
    EffortLag,
    Friction,
    LinearSpring,
    Quantisation,
    SensorDelay,
    SensorNoise,
    SensorStep,
    StanceLoad,
    ThermalSoftening,
    Viscoelastic,
)
from seadesign.effects import CurveRangeError, SpringCurve, TorqueCurve
from seadesign.errors import ConfigError

T = np.linspace(0.0, 20.0, 2001)
D = 0.3 * np.sin(2 * np.pi * 0.25 * T) + 0.05 * np.sin(2 * np.pi * 1.3 * T)


def _signals():
    return {"time": T.copy(), "deflection": D, "torque": 9.1 * D, "velocity": np.gradient(D, T), "angle": 1.0 + D,
            "stance": 0.5 + 0.5 * np.sin(T), "hall": 1.0 + D, "temperature": 30.0 + T, "effort": 9.1 * D}


# parameters that exercise each stateful effect's regime on the 20 s record: a step in mid-record, thermal
# softening that heats and cools by tens of percent, a hysteresis loop that saturates
STEPPING = {"sensor_step": {"time_s": 7.31, "size_rad": 0.09}, "thermal_softening": {"softening_per_J": 0.5,
            "cooling_time_s": 3.0}, "hysteresis": {"torque_Nm": 0.3, "stiffness_Nm_per_rad": 20.0}}


@pytest.mark.parametrize("key", sorted(k for k, c in LIBRARY.items() if c.stateful))
@pytest.mark.parametrize("uniform", [True, False], ids=["uniform", "jittered"])
def test_stepping_equals_apply(key, uniform):
    """Stateful effects have two implementations (per-sample `step`, vectorised `apply`): they must agree,
    on a uniform time grid (the vectorised filters) and a jittered one (the per-sample fallbacks)."""
    effect = LIBRARY[key](**STEPPING.get(key, {}))
    sig = _signals()
    if not uniform:
        sig["time"] = T + np.random.default_rng(1).uniform(0, 0.004, T.size)
        sig["time"][0] = 0.0
    T_ = sig["time"]
    whole = effect.apply(sig)
    state = effect.init_state({k: v[0:1] for k, v in sig.items()})
    stepped = [effect.step(state, {k: v[i:i + 1] for k, v in sig.items()}, T_[i] - T_[i - 1] if i else 0.0)[0]
               for i in range(T.size)]
    np.testing.assert_allclose(stepped, whole, rtol=0, atol=4e-14)  # measured at most 1.2e-14 (effort lag)
    if key in STEPPING:  # the regime is reached: the effect changes its target by more than a trace
        assert np.abs(whole - sig[effect.target()]).max() > 0.05


def test_every_parameter_has_unit_and_sane_bounds():
    for cls in LIBRARY.values():
        assert cls.summary and cls.writes
        for p in cls.parameters:
            assert p.unit and p.doc and p.lower <= p.default <= p.upper


def test_bounds_and_names_are_checked():
    with pytest.raises(ConfigError, match=r"width_rad = -1.0 rad is outside"):
        DeadBand(width_rad=-1.0)
    with pytest.raises(ConfigError, match="has no parameter 'width'"):
        DeadBand(width=0.1)
    with pytest.raises(ConfigError, match="needs signal 'deflection'"):
        DeadBand().apply({"time": T})


def test_dead_band_is_a_dead_zone_of_the_set_width():
    d = np.linspace(-0.2, 0.2, 401)
    out = DeadBand(width_rad=0.1).apply({"deflection": d})
    assert np.all(out[np.abs(d) <= 0.05] == 0)
    np.testing.assert_allclose(out[d > 0.05], d[d > 0.05] - 0.05)
    np.testing.assert_allclose(out[d < -0.05], d[d < -0.05] + 0.05)


def test_dahl_loop_saturates_and_is_rate_independent():
    th = 0.4
    eff = DahlHysteresis(torque_Nm=th, stiffness_Nm_per_rad=200.0)
    loops = []
    for f in (0.1, 1.0):
        t = np.linspace(0, 3 / f, 6001)
        d = 0.5 * np.sin(2 * np.pi * f * t)
        z = eff.apply({"deflection": d, "torque": np.zeros_like(d)})
        last = t >= 2 / f
        loops.append(np.trapezoid(z[last], d[last]))
        assert np.max(np.abs(z)) <= th + 1e-12
    # a saturated loop is a band of height 2 tau_h over a travel of 2 A: area about 4 tau_h A
    # measured 0.4 % short (the loop's finite slope after each reversal), and the same at both rates (the same samples)
    assert abs(loops[0]) == pytest.approx(4 * th * 0.5, rel=0.012)
    assert loops[0] == pytest.approx(loops[1], rel=1e-12)


def test_standard_linear_solid_relaxes_after_a_step():
    k2, tr = 3.0, 0.5
    t = np.linspace(0, 3, 3001)
    d = np.where(t > 0, 0.1, 0.0)
    d[0] = 0.0
    out = Viscoelastic(maxwell_stiffness_Nm_per_rad=k2, relaxation_time_s=tr).apply(
        {"deflection": d, "time": t, "torque": np.zeros_like(t)})
    expected = k2 * 0.1 * np.exp(-(t[1:] - t[1]) / tr) * np.exp(-(t[1] - t[0]) / tr)
    np.testing.assert_allclose(out[1:], expected, rtol=2e-11)  # measured 5.9e-12


@pytest.mark.parametrize("cooling_s", [1e6, 20.0])
def test_thermal_softening_heats_with_the_power_and_cools(cooling_s):
    """H' = f k |d d'| - H / tc, f = 1 - c H (the spring's own, softened, torque times its rate) integrated by
    scipy's solve_ivp (RK45, rtol 1e-9) while a sine drives the spring; then pure exponential cooling when held."""
    from scipy.integrate import solve_ivp

    c, k, w, amp = 2e-3, 9.1, 2 * np.pi * 0.5, 0.3
    eff = ThermalSoftening(softening_per_J=c, cooling_time_s=cooling_s)
    t = np.linspace(0.0, 40.0, 8001)
    drive = t < 20.0
    d = np.where(drive, amp * np.sin(w * t), 0.0)
    out = eff.apply({"deflection": d, "time": t, "torque": k * d})
    rhs = lambda s, h: (1 - c * h) * k * abs(amp * np.sin(w * s) * amp * w * np.cos(w * s)) - h / cooling_s  # noqa: E731
    sol = solve_ivp(rhs, (0.0, 20.0), [0.0], t_eval=t[drive], rtol=1e-9, atol=1e-12, max_step=0.01)
    moving = np.abs(d[drive]) > 0.1
    # measured 1.0e-5 here and 9.5e-6 for the cooling below
    np.testing.assert_allclose(out[drive][moving] / (k * d[drive][moving]), 1 - c * sol.y[0][moving], rtol=3e-5)
    # held still (no power): the heat left at the stop decays as exp(-(t - t_stop)/tc); probe it with a tiny deflection
    probe = np.where(drive, d, 1e-9)
    held = eff.apply({"deflection": probe, "time": t, "torque": np.where(drive, k * d, 1.0)})[~drive]
    h_stop = sol.y[0][-1]
    np.testing.assert_allclose(held, 1 - c * h_stop * np.exp(-(t[~drive] - t[drive][-1]) / cooling_s), rtol=3e-5)
    if cooling_s < 100:
        assert 1 - held[-1] < 0.4 * (1 - held[0])  # it has cooled off: 20 s at tc = 20 s leaves e^-1 of the loss


def test_sensor_step_effort_lag_and_drift():
    t = np.arange(1000) / 100.0
    step = SensorStep(time_s=4.0, size_rad=0.09).apply({"hall": np.zeros_like(t), "time": t + 7.0})
    np.testing.assert_array_equal(step, np.where(t >= 4.0, 0.09, 0.0))
    torque = np.where(t >= 1.0, 2.0, 0.0)
    lag = EffortLag(time_constant_s=0.05).apply({"effort": torque, "time": t})
    # measured 4e-16 (two units in the last place)
    np.testing.assert_allclose(lag[t >= 1.0], 2.0 * (1 - np.exp(-(t[t >= 1.0] - 1.0 + 0.01) / 0.05)), rtol=1.5e-15)
    back = EffortLag.torque_from_effort(lag, np.gradient(lag, t), 0.05)
    assert np.abs(back - torque)[t > 1.2].max() < 5e-4  # the inverse recovers the torque once the jump has passed (1.6e-4)


def test_friction_stance_delay_quantisation_wrap():
    v = np.array([-2.0, 0.0, 2.0])
    f = Friction(coulomb_Nm=0.1, viscous_Nm_s_per_rad=0.05, smoothing_rad_per_s=1e-4).apply({"velocity": v})
    np.testing.assert_allclose(f, [-0.2, 0.0, 0.2])
    q = np.array([np.pi / 2])
    load = StanceLoad(weight_N=40.0, upper_leg_m=0.2, lower_leg_m=0.2).apply({"angle": q, "stance": np.ones(1)})
    np.testing.assert_allclose(load, -40.0 * 0.2 * np.sin(np.pi / 4))
    delayed = SensorDelay(delay_s=0.5).apply({"hall": np.sin(T), "time": T})
    # 0.5 s is 50 samples: the shift is exact (measured 1.1e-16)
    np.testing.assert_allclose(delayed[T >= 0.5], np.sin(T[T >= 0.5] - 0.5), rtol=0, atol=5e-16)
    x = np.linspace(-10, 10, 1001)
    quant = Quantisation(bits=8).apply({"hall": x})
    assert np.max(np.abs(quant - x)) <= np.pi / 256 + 1e-12
    wrapped = AngleWrap().apply({"hall": x})
    assert np.all((wrapped >= -np.pi) & (wrapped < np.pi))
    # measured 0; rounding of |x| <= 10 is 1.8e-15
    np.testing.assert_allclose(np.mod(wrapped - x, 2 * np.pi) % (2 * np.pi), 0.0, atol=1e-14)


def test_disabled_effect_leaves_no_trace_in_a_chain():
    base = [DeadBand(width_rad=0.02), LinearSpring(k_Nm_per_rad=9.1),
            SensorNoise("hall_noise", std_rad=0.01)]
    extra = [DahlHysteresis(enabled=False), SensorNoise("other_noise", enabled=False)]
    sig = _signals()
    a = EffectChain(base).run(sig, seed=4)
    b = EffectChain(base[:2] + extra[:1] + base[2:] + extra[1:]).run(sig, seed=4)
    for key in a:
        np.testing.assert_array_equal(a[key], b[key])
    on = EffectChain(base[:2] + [extra[0].replace(enabled=True)] + base[2:]).run(sig, seed=4)
    assert not np.allclose(on["torque"], a["torque"])
    np.testing.assert_array_equal(on["hall"], a["hall"])  # the noise stream does not depend on other effects


def test_chain_configure_and_unique_names():
    chain = EffectChain([DeadBand("a"), DeadBand("b", enabled=False)])
    assert chain.configure("b", enabled=True, width_rad=0.2)["b"].values["width_rad"] == 0.2
    with pytest.raises(ConfigError, match="no effect named 'c'"):
        chain.configure("c")
    with pytest.raises(ConfigError, match="unique"):
        EffectChain([DeadBand("a"), DeadBand("a")])


# a rotation-driven CalculiX NLGEOM run of ours (4 beams x 8 mm, neo-Hookean from E 12 MPa and nu 0.48, coarse mesh of
# 159k degrees of freedom, linear k 19.15 Nm/rad; CalculiX stopped converging at 0.48 rad): torque falls off with rotation
CURVE_RAD = (0.0, 0.05, 0.10, 0.20, 0.30, 0.40, 0.45, 0.475)
CURVE_NM = (0.0, 0.941, 1.845, 3.504, 4.907, 5.973, 6.361, 6.517)


def test_torque_curve_is_monotone_odd_and_inverted_exactly():
    from scipy.optimize import brentq

    curve = TorqueCurve(CURVE_RAD, CURVE_NM, stop_reason="unconverged")
    th = np.linspace(-0.475, 0.475, 2001)
    tq = curve.torque(th)
    assert np.all(np.diff(tq) > 0)  # monotone between the points (PCHIP), not only at them
    np.testing.assert_allclose(curve.torque(np.array(CURVE_RAD)), CURVE_NM, rtol=0, atol=1e-14)  # measured 0
    np.testing.assert_allclose(curve.torque(-th), -tq)
    probe = np.array([-6.4, -3.0, -0.2, 0.0, 0.5, 1.845, 4.0, 6.5])
    ref = [np.sign(v) * brentq(lambda x: float(curve.torque(np.array([x]))[0]) - abs(v), 0, 0.475, xtol=1e-14)
           for v in probe]
    np.testing.assert_allclose(curve.rotation(probe), ref, rtol=0, atol=3e-14)  # brentq's xtol 1e-14; measured 2e-15
    spring = SpringCurve(curve, scale=0.5)
    np.testing.assert_allclose(spring.apply({"deflection": th}), 0.5 * tq)
    np.testing.assert_allclose(spring.rotation(0.5 * tq), th, rtol=0, atol=5e-16)  # measured 1.7e-16


def test_torque_curve_refuses_to_extrapolate_unless_a_hard_stop():
    curve = TorqueCurve(CURVE_RAD, CURVE_NM, stop_reason="limit_point")
    with pytest.raises(CurveRangeError, match=r"rotation 0.5 rad is past .* 0.475 rad, 6.517 Nm .*limit_point"):
        curve.torque(np.array([0.1, -0.5]))
    with pytest.raises(CurveRangeError, match=r"torque 7 Nm is past"):
        curve.rotation(np.array([7.0]))
    stop = TorqueCurve(CURVE_RAD, CURVE_NM, stop_reason="contact", hard_stop=True)
    np.testing.assert_allclose(stop.rotation(np.array([7.0, -9.0])), [0.475, -0.475])
    np.testing.assert_allclose(stop.torque(np.array([0.6])), [6.517])
    with pytest.raises(ConfigError, match="torque_curve/torque_Nm must increase strictly"):
        TorqueCurve((0.0, 0.1, 0.2), (0.0, 1.0, 1.0))
    with pytest.raises(ConfigError, match="must start at"):
        TorqueCurve((0.01, 0.1, 0.2), (0.0, 1.0, 2.0))
    with pytest.raises(ConfigError, match="stop_reason 'done'"):
        TorqueCurve.from_handoff({"rotation_rad": CURVE_RAD, "torque_Nm": CURVE_NM, "stop_reason": "done"})


K = 9.106


# measured worst relative errors (stiffness / compliance direction): 1.2e-4 / 1.5e-4 at a fifth of softening,
# 2.9e-3 / 2.2e-2 at 70 %
@pytest.mark.parametrize("c, compliance, softest, rtol", [(1e-3, False, 0.85, 3.5e-4), (1e-3, True, 0.85, 4.5e-4),
                                                          (6e-3, False, 0.35, 9e-3), (6e-3, True, 0.35, 0.067)])
def test_marched_softening_matches_the_per_sample_effect(c, softest, rtol, compliance):
    """The fitter's chunked march (f held per 25 samples, closed form there) against the library's per-sample
    implicit recursion: from the known deflection (stiffness direction), or from the torque and torque / k
    alone (compliance direction), to a quarter and to two thirds of softening."""
    from seadesign.effects.spring import softening_marched

    t = np.arange(12000) / 100.0
    d = 0.5 * np.sin(2 * np.pi * 0.5 * t)
    torque = ThermalSoftening().apply({"deflection": d, "torque": K * d, "time": t},
                                      {"softening_per_J": c, "cooling_time_s": 300.0})
    x = torque / K if compliance else d
    work = (torque if compliance else K * d) * np.diff(x, prepend=x[0])
    f = softening_marched(np.abs(work), 0.01, c, 300.0, compliance)
    moving = np.abs(d) > 0.1
    truth = torque[moving] / (K * d[moving])
    assert truth.min() < softest  # the case softens as stated
    np.testing.assert_allclose(f[moving], truth, rtol=rtol)


@pytest.mark.parametrize("torque, stiffness", [(0.3, 50.0), (0.03, 500.0), (0.0066, 30.0), (1.0, 0.5)])
def test_vectorised_dahl_equals_the_effect_library(torque, stiffness):
    """The block-wise Dahl solution (`apply`) against the per-sample recursion (`step`), on a sine with a
    random walk (many small reversals), from slow to instant saturation."""
    from seadesign.effects.spring import dahl

    t = np.arange(20000) / 100.0
    d = 0.5 * np.sin(2 * np.pi * 0.3 * t) + np.cumsum(np.random.default_rng(0).normal(0, 0.003, t.size))
    eff = DahlHysteresis(torque_Nm=torque, stiffness_Nm_per_rad=stiffness)
    state = eff.init_state({"deflection": d[:1], "torque": np.zeros(1)})
    ref = [eff.step(state, {"deflection": d[i:i + 1], "torque": np.zeros(1)}, 0.01)[0] for i in range(d.size)]
    np.testing.assert_allclose(dahl(d, torque, stiffness), ref, rtol=0, atol=1e-13 * torque)  # measured 3.1e-14 tau_h


@pytest.mark.parametrize("torque, stiffness", [(0.3, 50.0), (0.1, 3.0), (0.05, 900.0)])
def test_dahl_in_series_shares_the_torque_with_the_spring(torque, stiffness):
    """A Dahl loop in parallel with the spring k carrying k x: the closed form along each stretch of one direction
    (`dahl_in_series`) against d found sample by sample by brentq from k d + z(d) = k x, z stepped from the previous
    sample by the Dahl law's exact step for a monotonic move (z -> s tau_h + (z - s tau_h) exp(-sigma |dd| / tau_h)),
    on a sine with a random walk; the loop softer than, as stiff as and 100 times stiffer than the spring."""
    from scipy.optimize import brentq

    from seadesign.effects.spring import dahl_in_series

    t = np.arange(2000) / 100.0
    x = 0.1 * np.sin(2 * np.pi * 0.3 * t) + np.cumsum(np.random.default_rng(2).normal(0, 0.002, t.size))
    z, d, ref = 0.0, x[0], []
    for xn in x:
        def residual(dn, z=z, d=d):
            s = np.sign(dn - d)
            return K * dn + s * torque + (z - s * torque) * np.exp(-stiffness * abs(dn - d) / torque) - K * xn
        d = brentq(residual, xn - 1.01 * torque / K, xn + 1.01 * torque / K, xtol=1e-15, rtol=1e-15)
        z = K * (xn - d)
        ref.append(z)
    # measured: at most 4.2e-13 tau_h (the plain `dahl` of x, the loop not sharing the torque, is off by 0.08-1.4 tau_h)
    np.testing.assert_allclose(dahl_in_series(x, torque, stiffness, K), ref, rtol=0, atol=1.5e-12 * torque)


def test_torque_curve_pieces_are_scipys_pchip_to_the_last_digit_and_differentiate_in_torch():
    """The curve is evaluated from its PCHIP pieces in any array namespace: NumPy gives scipy's `PchipInterpolator`
    exactly (the same sums in the same order), torch the same values to round-off, and a gradient that is the
    interpolant's derivative."""
    import array_api_compat.torch as xp
    import torch
    from scipy.interpolate import PchipInterpolator

    curve = TorqueCurve(CURVE_RAD, CURVE_NM)
    th = np.random.default_rng(4).uniform(-CURVE_RAD[-1], CURVE_RAD[-1], 20000)
    th[:len(CURVE_RAD)] = CURVE_RAD
    pchip = PchipInterpolator(CURVE_RAD, CURVE_NM)
    assert np.array_equal(curve.torque(th), np.sign(th) * pchip(np.abs(th)))
    t = torch.tensor(th, requires_grad=True)
    tq = curve.torque(t, xp=xp)
    tq.sum().backward()
    np.testing.assert_allclose(tq.detach().numpy(), curve.torque(th), rtol=0, atol=1e-14)  # measured 0
    moving = th != 0  # sign(theta) has no gradient at 0
    np.testing.assert_allclose(t.grad.numpy()[moving], pchip.derivative()(np.abs(th[moving])), rtol=1e-12, atol=1e-12)
    with pytest.raises(CurveRangeError, match="past the spring's torque curve"):
        curve.torque(torch.tensor([CURVE_RAD[-1] * 1.01]), xp=xp)


@pytest.mark.parametrize("key", sorted(LIBRARY))
def test_one_step_definition_gives_numpy_and_torch_the_same_numbers(key):
    """Each effect's time step is written once (`Effect.advance` against an array namespace): stepped on torch
    tensors (exact options) it gives what it gives on NumPy arrays, sample by sample, states included; a random
    effect draws from the stream it is given."""
    import array_api_compat.torch as xp
    import torch

    effect = LIBRARY[key](**STEPPING.get(key, {}))
    sig = _signals()
    batch = {k: np.stack([v, 0.7 * v]) for k, v in sig.items()}  # a batch of two, time last
    tensors = {k: torch.tensor(v) for k, v in batch.items()}

    class Draws:  # the same "draws" for both namespaces
        def __init__(self, ones):
            self.ones = ones

        def standard_normal(self, shape):
            return 0.01 * self.ones(shape, dtype=float)

    state_np = effect.init_state({k: v[:, 0] for k, v in batch.items()})
    state_t = effect.init_state({k: v[:, 0] for k, v in tensors.items()}, None, xp)
    worst = 0.0
    for i in range(0, T.size, 7):
        dt = float(T[i] - T[i - 7]) if i else 0.0
        a, state_np = effect.advance(state_np, {k: v[:, i] for k, v in batch.items()}, dt, rng=Draws(np.ones))
        b, state_t = effect.advance(state_t, {k: v[:, i] for k, v in tensors.items()}, dt, rng=Draws(torch.ones), xp=xp)
        worst = max(worst, float(np.abs(b.numpy() - a).max()))
    assert worst <= 1e-15  # measured 0
