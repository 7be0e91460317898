"""Change-point detection (`seadesign.calibration.changepoint`) against the ruptures library it stands in for, and the
engine's search window for a sensor step (10-90 % of the record) on robot-format recordings."""

from __future__ import annotations

import numpy as np
import pytest

from helpers_generators import robot
from seadesign.calibration import explain
from seadesign.calibration.changepoint import best_split, split_gains
from seadesign.calibration.sea import robot_loop_data


@pytest.mark.parametrize("seed", range(5))
def test_best_split_is_ruptures_binseg_l2_with_one_break(seed):
    ruptures = pytest.importorskip("ruptures", reason="ruptures (a test dependency) is not installed")
    rng = np.random.default_rng(seed)
    n = int(rng.integers(300, 3000))
    jump = int(rng.integers(n // 5, 4 * n // 5))
    x = rng.normal(0, 0.02, n) + 0.01 * np.sin(np.arange(n) / 40.0)
    x[jump:] += rng.uniform(0.01, 0.05) * rng.choice([-1, 1])
    ref = ruptures.Binseg(model="l2", min_size=20, jump=1).fit(x).predict(n_bkps=1)[0]
    assert best_split(x, min_size=20) == ref


def test_split_gains_are_the_drop_in_the_sum_of_squares():
    x = np.random.default_rng(1).normal(size=200)
    ssr = lambda a: float(np.sum((a - a.mean()) ** 2))  # noqa: E731
    brute = [ssr(x) - ssr(x[:i]) - ssr(x[i:]) for i in range(1, 200)]
    np.testing.assert_allclose(split_gains(x), brute, rtol=1e-9, atol=1e-9)


def test_ends_and_taken_segments_are_excluded():
    x = np.zeros(1000)
    x[:30] = 1.0  # a shift at the start is an offset, not a step
    x[600:] += 0.5
    assert best_split(x, min_size=50) == 600
    assert best_split(x, min_size=50, exclude=[600]) not in range(590, 611)
    assert best_split(np.zeros(60), min_size=50) is None


def test_a_shift_beyond_the_window_is_no_split_when_interior():
    """A shift nearer an end than `min_size` puts the largest gain at the window's edge: there, not at the shift."""
    x = np.zeros(1000)
    x[50:] += 1.0
    assert best_split(x, min_size=100) == 100
    assert best_split(x, min_size=100, interior=True) is None
    assert best_split(x[::-1].copy(), min_size=100, interior=True) is None
    x[500:] += 0.5  # an interior shift is still found
    assert best_split(x, min_size=100, interior=True) == 500


def test_a_sensor_step_nearer_the_start_than_the_window_is_an_offset(spring_dict):
    """A Hall jump of 0.08 rad at 3 s of 60 s (5 %, before the window's 6 s): no sensor step is named (none at the
    window's edge, the wrong instant); over the training samples the jump is an offset of 0.08 x 45 / 48 (48 s of
    training, 3 s of it before the jump) = 0.075 rad."""
    ex = explain(robot_loop_data(robot({"sensor_step": {"size_rad": 0.08, "time_s": 3.0}}, seed=20), spring_dict), [],
                 max_steps=2)
    assert ex.found == ["sensor_offset"], ex.verdict()
    # measured 0.07471 (0.4 % off)
    assert ex.final.parameters()["sensor_offset"]["offset_rad"]["value"] == pytest.approx(0.08 * 45 / 48, rel=0.012)


def test_a_sensor_step_just_inside_the_window_is_found_at_its_instant(spring_dict):
    """A Hall jump of 0.08 rad at 6.1 s of 60 s, ten samples inside the window: named at its instant (to one sample)
    and its size recovered (measured: 6.1 s exactly, 0.07989 rad, 0.14 % off)."""
    ex = explain(robot_loop_data(robot({"sensor_step": {"size_rad": 0.08, "time_s": 6.1}}, seed=20), spring_dict), [],
                 max_steps=2)
    assert ex.found == ["sensor_step"], ex.verdict()
    p = ex.final.parameters()["sensor_step"]
    assert p["time_s"]["value"] == pytest.approx(6.1, abs=0.011)
    assert p["size_rad"]["value"] == pytest.approx(0.08, rel=0.005)
