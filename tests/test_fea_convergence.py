"""Richardson extrapolation recovers a known limit and order."""

import numpy as np
import pytest

from seadesign.fea.convergence import richardson


@pytest.mark.parametrize("p", [1.0, 2.0, 3.0])
def test_richardson_recovers_limit_and_order(p):
    h = [3.0, 2.0, 1.5, 1.2]
    r = richardson(h, [10.0 + 0.7 * x**p for x in h])
    assert r["extrapolated"] == pytest.approx(10.0, rel=1e-9)
    assert r["order"] == pytest.approx(p, rel=1e-6)
    assert r["rel_error_h=1.2"] == pytest.approx(0.7 * 1.2**p / 10.0, rel=1e-6)


@pytest.mark.parametrize("values", [[10.0, 9.0, 9.5], [10.0, 9.9, 9.0]])  # not monotone; differences growing
def test_series_outside_the_asymptotic_range_gives_no_estimate(values):
    r = richardson([3, 2, 1], values)
    assert np.isnan(r["order"]) and np.isnan(r["extrapolated"]) and np.isnan(r["rel_error_h=1"])
