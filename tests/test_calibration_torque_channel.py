"""A bench's torque channel behind its deflection channel (a filtered load-cell amplifier, or a pure delay):
named as a lag of the torque reading, with its size, on bench tests written by `helpers_generators.bench_curve`
(apart from the effect library: the delay evaluated exactly, the low-pass by explicit Euler substeps).

At the bench's 0.1 and 0.37 Hz a pure delay and a first-order low-pass of about the same size fit equally well
(measured: held-out RMSE within 0.6 % at 30 ms), and the loop says so: the winner with the other as the
ambiguity. From about 50 ms (low-pass) and 100 ms (delay) the held-out error tells them apart. Measured errors
of the fitted value: 0.07-0.58 %. Floor: a low-pass shorter than about half the
sample interval (5 ms at 100 Hz) is not seen, for the sampled filter passes each sample almost whole."""

from __future__ import annotations

import pytest

from helpers_generators import K, bench_curve
from seadesign.calibration import explain
from seadesign.calibration.sea import bench_loop_data


def linear(theta):
    return K * theta


def lag_named(ex, name: str, parameter: str) -> float:
    """The fitted value of the torque channel's `name`: the winner, or the ambiguity's alternative when the data
    cannot tell the two forms apart; nothing else named."""
    assert [f for f in ex.found if f != "stiffness_scale"] in (["torque_lag"], ["torque_delay"]), ex.verdict()
    if ex.found[-1] == name:
        return ex.final.parameters()[name][parameter]["value"]
    assert ex.ambiguities == [(ex.found[-1], name)], ex.verdict()
    return ex.steps[-1].alternative.fit.parameters()[name][parameter]["value"]


@pytest.mark.parametrize("time_constant_s", [0.02, 0.05, 0.1])
def test_a_low_pass_torque_channel_is_named_with_its_time_constant(spring_dict, time_constant_s):
    df = bench_curve(linear, 1.0, 0.5, seed=int(1000 * time_constant_s), torque_time_constant_s=time_constant_s)
    ex = explain(bench_loop_data(df, spring_dict), [])
    assert lag_named(ex, "torque_lag", "time_constant_s") == pytest.approx(time_constant_s, rel=0.02)
    if time_constant_s >= 0.05:
        assert ex.found[-1] == "torque_lag" and not ex.ambiguities, ex.verdict()
    assert "The torque reading lags the deflection reading" in ex.verdict()


@pytest.mark.parametrize("delay_s", [0.01, 0.03, 0.1])
def test_a_delayed_torque_channel_is_named_with_its_delay(spring_dict, delay_s):
    df = bench_curve(linear, 1.0, 0.5, seed=int(1000 * delay_s) + 1, torque_delay_s=delay_s)
    ex = explain(bench_loop_data(df, spring_dict), [])
    assert lag_named(ex, "torque_delay", "delay_s") == pytest.approx(delay_s, rel=0.02)
    if delay_s >= 0.1:  # far enough from a low-pass for the held-out error to choose
        assert ex.found[-1] == "torque_delay" and not ex.ambiguities, ex.verdict()


def test_the_bench_simulator_lags_its_torque_channel_and_the_loop_finds_it(spring_dict):
    """`simulate-bench --effect torque_lag:...`: the library's filter on the simulator's torque channel."""
    import seadesign as sd

    table, meta = sd.simulate_bench(spring_dict, profile="sine", frequency_hz=0.2, duration_s=60.0,
                                    effects=("torque_lag:time_constant_s=0.1",))
    assert "torque_lag" in meta["effects_enabled"]
    ex = explain(bench_loop_data(table, spring_dict), [])
    assert lag_named(ex, "torque_lag", "time_constant_s") == pytest.approx(0.1, rel=0.003)  # measured 0.05 %
