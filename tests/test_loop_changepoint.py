"""Change-point detection (`seadesign.loop.changepoint`) against the ruptures library it stands in for."""

from __future__ import annotations

import numpy as np
import pytest

from seadesign.loop.changepoint import best_split, split_gains

ruptures = pytest.importorskip("ruptures", reason="ruptures (a test dependency) is not installed")


@pytest.mark.parametrize("seed", range(5))
def test_best_split_is_ruptures_binseg_l2_with_one_break(seed):
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
