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
    Friction,
    LinearSpring,
    Quantisation,
    SensorDelay,
    SensorNoise,
    StanceLoad,
    ThermalSoftening,
    Viscoelastic,
)
from seadesign.errors import ConfigError

T = np.linspace(0.0, 20.0, 2001)
D = 0.3 * np.sin(2 * np.pi * 0.25 * T) + 0.05 * np.sin(2 * np.pi * 1.3 * T)


def _signals():
    return {"time": T, "deflection": D, "torque": 9.1 * D, "velocity": np.gradient(D, T), "angle": 1.0 + D,
            "stance": 0.5 + 0.5 * np.sin(T), "hall": 1.0 + D, "temperature": 30.0 + T}


@pytest.mark.parametrize("key", sorted(k for k, c in LIBRARY.items() if not c.random))
def test_stepping_equals_apply(key):
    effect = LIBRARY[key]()
    sig = _signals()
    whole = effect.apply(sig)
    state = effect.init_state({k: v[0:1] for k, v in sig.items()})
    stepped = [effect.step(state, {k: v[i:i + 1] for k, v in sig.items()}, T[i] - T[i - 1] if i else 0.0)[0]
               for i in range(T.size)]
    np.testing.assert_allclose(stepped, whole, atol=1e-12)


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
    assert abs(loops[0]) == pytest.approx(4 * th * 0.5, rel=0.05)
    assert loops[0] == pytest.approx(loops[1], rel=1e-3)


def test_standard_linear_solid_relaxes_after_a_step():
    k2, tr = 3.0, 0.5
    t = np.linspace(0, 3, 3001)
    d = np.where(t > 0, 0.1, 0.0)
    d[0] = 0.0
    out = Viscoelastic(maxwell_stiffness_Nm_per_rad=k2, relaxation_time_s=tr).apply(
        {"deflection": d, "time": t, "torque": np.zeros_like(t)})
    expected = k2 * 0.1 * np.exp(-(t[1:] - t[1]) / tr) * np.exp(-(t[1] - t[0]) / tr)
    np.testing.assert_allclose(out[1:], expected, rtol=1e-9)


def test_thermal_softening_follows_dissipated_energy():
    eff = ThermalSoftening(softening_per_K=0.01, loss_factor=0.2, heat_capacity_J_per_K=10.0, cooling_time_s=1e6)
    torque = 9.1 * D
    out = eff.apply({"deflection": D, "time": T, "torque": torque})
    energy = np.concatenate([[0.0], np.cumsum(np.abs(torque[1:] * np.diff(D)))])
    expected = torque * (1 - 0.01 * 0.2 * energy / 10.0 * np.exp(-(T - T) / 1e6))
    np.testing.assert_allclose(out, expected, rtol=1e-4, atol=1e-9)
    still = eff.apply({"deflection": np.full_like(T, 0.2), "time": T, "torque": np.full_like(T, 1.8)})
    assert np.all(still == 1.8)


def test_friction_stance_delay_quantisation_wrap():
    v = np.array([-2.0, 0.0, 2.0])
    f = Friction(coulomb_Nm=0.1, viscous_Nm_s_per_rad=0.05, smoothing_rad_per_s=1e-4).apply({"velocity": v})
    np.testing.assert_allclose(f, [-0.2, 0.0, 0.2])
    q = np.array([np.pi / 2])
    load = StanceLoad(weight_N=40.0, upper_leg_m=0.2, lower_leg_m=0.2).apply({"angle": q, "stance": np.ones(1)})
    np.testing.assert_allclose(load, -40.0 * 0.2 * np.sin(np.pi / 4))
    delayed = SensorDelay(delay_s=0.5).apply({"hall": np.sin(T), "time": T})
    np.testing.assert_allclose(delayed[T >= 0.5], np.sin(T[T >= 0.5] - 0.5), atol=2e-5)
    x = np.linspace(-10, 10, 1001)
    quant = Quantisation(bits=8).apply({"hall": x})
    assert np.max(np.abs(quant - x)) <= np.pi / 256 + 1e-12
    wrapped = AngleWrap().apply({"hall": x})
    assert np.all((wrapped >= -np.pi) & (wrapped < np.pi))
    np.testing.assert_allclose(np.mod(wrapped - x, 2 * np.pi) % (2 * np.pi), 0.0, atol=1e-9)


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
