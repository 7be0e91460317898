"""The large-deflection torque curve as the loop's spring (spring.json `torque_curve`) instead of k."""

from __future__ import annotations

import numpy as np
import pytest

from helpers_generators import K, robot
from seadesign.effects import CurveRangeError
from seadesign.calibration import explain
from seadesign.calibration.sea import robot_loop_data

K3 = -80.0  # the generator's spring softens: T = k d + K3 d^3 (monotone up to 0.19 rad)


def curve(end_rad: float, hard_stop: bool = False) -> dict:
    theta = np.linspace(0.0, end_rad, 7)
    return {"rotation_rad": theta.tolist(), "torque_Nm": (K * theta + K3 * theta ** 3).tolist(),
            "source": "fea_large_deflection", "stop_reason": "limit_point", "hard_stop": hard_stop}


@pytest.fixture(scope="module")
def softening_knee():
    return robot({"cubic_stiffening": {"k3_Nm_per_rad3": K3}}, seed=50)


def test_a_schema_2_spring_json_with_the_curve_loads_and_is_the_models_spring(tmp_path, spring_dict):
    from seadesign.design.spring import load_spring, torque_curve, write_spring
    from seadesign.effects import SpringCurve, spring_law

    path = write_spring({**spring_dict, "schema_version": 2, "torque_curve": curve(0.17)}, tmp_path / "spring.json")
    loaded = load_spring(path)
    spring = spring_law(loaded["k_Nm_per_rad"], torque_curve(loaded))
    assert isinstance(spring, SpringCurve) and spring.curve.end_rotation_rad == pytest.approx(0.17)


def test_curve_is_the_spring_and_explains_the_softening(spring_dict, softening_knee):
    linear = explain(robot_loop_data(softening_knee, spring_dict), [], max_steps=1)
    assert linear.found == ["cubic_stiffening"], linear.verdict()
    assert linear.final.parameters()["cubic_stiffening"]["k3_Nm_per_rad3"]["value"] == pytest.approx(K3, rel=0.05)  # [0.021]
    with_curve = explain(robot_loop_data(softening_knee, {**spring_dict, "torque_curve": curve(0.17)}), [], max_steps=1)
    assert with_curve.found == [], with_curve.verdict()
    # the curve (7 PCHIP points) predicts as well as the fitted cubic, from the start (measured 0.05 % worse), and its
    # scale is 1 (measured 1.0064)
    assert with_curve.plain.errors["held_out"]["rmse"] < 1.002 * linear.final.errors["held_out"]["rmse"]
    assert with_curve.final.parameters()["stiffness_scale"]["scale"]["value"] == pytest.approx(1.0, abs=0.02)


def test_data_past_the_curve_are_left_out_not_extrapolated(spring_dict, softening_knee):
    """A robot recording whose deflection goes past the curve's end: those samples are left out of the fit and
    counted (never extrapolated), the rest still says the spring is the declared one; a record with fewer than half
    its samples on the curve is refused, naming the range the curve covers."""
    data = robot_loop_data(softening_knee, {**spring_dict, "torque_curve": curve(0.05)})
    motor_minus_hall = (softening_knee["l_knee_pos"] - softening_knee["l_hall_pos"]).abs().to_numpy()
    assert data.coverage is not None and data.coverage.excluded == pytest.approx((motor_minus_hall > 0.05).sum(), rel=0.03)
    ex = explain(data, [])
    assert ex.found == [], ex.verdict()
    scale = ex.final.parameters()["stiffness_scale"]["scale"]
    assert abs(scale["value"] - 1.0) <= 3 * scale["uncertainty"]  # measured 1.0048 +- 0.0038
    assert "left out of the fit" in ex.verdict()
    with pytest.raises(CurveRangeError, match=r"\d+ of 6000 samples \(55%\) are past the spring's torque curve, "
                                              r"which covers deflections up to 0\.03 rad"):
        robot_loop_data(softening_knee, {**spring_dict, "torque_curve": curve(0.03)})
    stop = robot_loop_data(softening_knee, {**spring_dict, "torque_curve": curve(0.05, hard_stop=True)})
    assert stop.in_range.all() and stop.coverage is None  # a hard stop holds the rotation at the end instead
