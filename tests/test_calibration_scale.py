"""Recover how soft or stiff the printed part really is: bench tests of springs 0.2 to 3 times the model's
stiffness, on a linear spring (k) and on a torque curve (spring.json's `torque_curve`), each fitted to the true
scale within three reported uncertainties with no other effect named; and bench data past the curve's end left
out and counted instead of refused.

Generators: `helpers_generators.bench` (linear) and `bench_curve` (a closed-form softening law, not the library's
PCHIP curve), written apart from the effect library. The curve is stored here, not taken from the default sweep."""

from __future__ import annotations

import numpy as np
import pytest

from helpers_generators import bench, bench_curve
from seadesign.effects import CurveRangeError
from seadesign.calibration import explain
from seadesign.calibration.sea import bench_loop_data

SCALES = [0.2, 0.5, 2.0, 3.0]


def softening_torque(theta):
    """The true spring (Nm): T = 30 theta (1 - 0.8 |theta|), softening like the default study's paths."""
    return 30.0 * theta * (1.0 - 0.8 * np.abs(theta))


# the stored curve: 16 points to 0.3 rad (6.84 Nm), ending where a path stopped at a bifurcation
CURVE_ROTATION_RAD = np.linspace(0.0, 0.3, 16)
CURVE = {"rotation_rad": CURVE_ROTATION_RAD.tolist(), "torque_Nm": softening_torque(CURVE_ROTATION_RAD).tolist(),
         "source": "fea_large_deflection", "stop_reason": "bifurcation", "hard_stop": False}


def recovered(ex, scale: float) -> dict:
    """The fitted stiffness scale, checked: named alone, within three of its uncertainties of `scale`."""
    assert ex.found == ["stiffness_scale"] and not ex.ambiguities, ex.verdict()
    fitted = ex.final.parameters()["stiffness_scale"]["scale"]
    assert not fitted["at_bound"]
    assert abs(fitted["value"] - scale) <= 3 * fitted["uncertainty"], fitted
    return fitted


@pytest.mark.parametrize("scale", SCALES)
def test_the_scale_of_a_linear_spring_comes_back(spring_dict, scale):
    df = bench({"stiffness_scale": {"scale": scale}}, seed=int(10 * scale))
    recovered(explain(bench_loop_data(df, spring_dict), []), scale)


@pytest.mark.parametrize("scale", SCALES)
def test_the_scale_of_a_torque_curve_comes_back(spring_dict, scale):
    """The issue's case at 0.5: a part twice as soft as the curve, its bench test inside the curve's range."""
    df = bench_curve(softening_torque, scale, amplitude_rad=0.28, seed=int(10 * scale))
    data = bench_loop_data(df, {**spring_dict, "torque_curve": CURVE})
    assert data.coverage is None and data.in_range.all()
    recovered(explain(data, []), scale)


def test_bench_data_past_the_curve_are_left_out_and_counted(spring_dict):
    """A bench test that goes 30 % past the curve's end: the samples beyond it are left out of the fit and
    counted, the scale still comes back, and the report says where the measurement left the model and why the
    curve ended."""
    df = bench_curve(softening_torque, 0.5, amplitude_rad=0.39, seed=3)
    data = bench_loop_data(df, {**spring_dict, "torque_curve": CURVE})
    beyond = np.abs(df["deflection_rad"].to_numpy()) > 0.3
    assert data.coverage is not None
    assert data.coverage.excluded == pytest.approx(beyond.sum(), abs=0.02 * beyond.sum())  # smoothed vs raw
    assert 0.05 < data.coverage.excluded / data.n < 0.5
    ex = explain(data, [])
    recovered(ex, 0.5)
    assert f"{data.coverage.excluded} of {data.n} samples" in ex.verdict()
    assert "the curve ends at 0.3 rad, 6.84 Nm (stop reason 'bifurcation')" in ex.verdict()
    assert "the measurement went where the model does not follow" in ex.verdict().lower()


def test_a_record_mostly_past_the_curve_is_refused_with_the_range(spring_dict):
    df = bench_curve(softening_torque, 0.5, amplitude_rad=1.2, seed=4)
    with pytest.raises(CurveRangeError, match=r"are past the spring's torque curve, which covers deflections up to "
                                              r"0\.3 rad \(6\.84 Nm; it ends with stop reason 'bifurcation'\)"):
        bench_loop_data(df, {**spring_dict, "torque_curve": CURVE})
