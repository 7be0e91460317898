"""The loop on robot recordings simulated with one or two undeclared effects.

Each case draws its parameters from a seeded range and runs the knee simulator (left knee data,
60 s walking forward at 0.2 m/s on the ground, 100 Hz, with the simulator's sensor noise,
quantisation and gear friction), then explains the Hall angle with the robot adapter: motor
angle minus the deflection the effort implies through the declared chain. The engine must name
the simulated effect first, recover its parameter within the stated relative tolerance (the
truth in the adapter's units: terms of the spring relative to k in this compliance direction)
and cut the held-out RMSE by the stated factor. Dead-band and friction are declared by default
(backlash and gear friction); their cases leave them out of the model instead.
"""

from __future__ import annotations

import numpy as np
import pytest

from seadesign.loop import explain
from seadesign.loop.sea import ROBOT_DECLARED, robot_loop_data
from seadesign.twin import KneeConfig, Trial, knee_effects, simulate

TRIAL = Trial("front", 0.2, 60.0)


def robot_data(spring: dict, effects: dict[str, dict[str, float]], declared=ROBOT_DECLARED, seed: int = 1):
    chain = knee_effects(KneeConfig.from_spring(spring), ground=True)
    for name, values in effects.items():
        chain = chain.configure(name, enabled=True, **values)
    df, _ = simulate(spring, [TRIAL], ground=True, effects=chain, seed=seed)
    return robot_loop_data(df, spring, "l", declared)


def draw(seed: int, lo: float, hi: float) -> float:
    return float(np.random.default_rng(seed).uniform(lo, hi))


# label, simulator effects from the value, declared, range, loop effect, parameter, truth(value, k, backlash), tol, factor
CASES = [
    ("dead_band", lambda v: {"dead_band": {"width_rad": v}}, ("friction",), (0.02, 0.05), "dead_band", "width",
     lambda v, k, b: v + b, 0.10, 2.0),
    ("friction", lambda v: {"gear_friction": {"coulomb_Nm": v}}, ("dead_band",), (0.2, 0.4), "friction", "coulomb",
     lambda v, k, b: v / k, 0.10, 3.0),
    ("stiffness_scale", lambda v: {"stiffness_scale": {"scale": v}}, ROBOT_DECLARED, (0.6, 0.85), "stiffness_scale",
     "scale", lambda v, k, b: v, 0.02, 10.0),
    ("cubic", lambda v: {"cubic_stiffening": {"k3_Nm_per_rad3": v}}, ROBOT_DECLARED, (4.0, 10.0), "cubic_stiffening",
     "k3_ratio", lambda v, k, b: v / k, 0.05, 5.0),
    ("hysteresis", lambda v: {"hysteresis": {"torque_Nm": v, "stiffness_Nm_per_rad": 50.0}}, ROBOT_DECLARED,
     (0.25, 0.4), "hysteresis", "deflection", lambda v, k, b: v / k, 0.15, 2.0),
    ("viscoelastic", lambda v: {"viscoelastic": {"maxwell_stiffness_Nm_per_rad": v, "relaxation_time_s": 0.5}},
     ROBOT_DECLARED, (2.0, 4.0), "viscoelastic", "maxwell_ratio", lambda v, k, b: v / k, 0.10, 3.0),
    ("thermal", lambda v: {"thermal_softening": {"softening_per_K": v, "loss_factor": 0.02,
                                                 "heat_capacity_J_per_K": 1.0, "cooling_time_s": 300.0}},
     ROBOT_DECLARED, (0.008, 0.012), "thermal_softening", "softening_per_J", lambda v, k, b: 0.02 * v, 0.10, 3.0),
    ("offset", lambda v: {"hall_offset": {"offset_rad": v}}, ROBOT_DECLARED, (0.01, 0.03), "sensor_offset", "offset",
     lambda v, k, b: v, 0.05, 2.0),
    ("drift", lambda v: {"hall_drift": {"rate_rad_per_s": v}}, ROBOT_DECLARED, (3e-4, 5e-4), "sensor_drift", "rate",
     lambda v, k, b: v, 0.10, 1.5),
    ("delay", lambda v: {"hall_delay": {"delay_s": v}}, ROBOT_DECLARED, (0.03, 0.07), "sensor_delay", "delay",
     lambda v, k, b: v, 0.10, 5.0),
]


@pytest.mark.parametrize("case", CASES, ids=[c[0] for c in CASES])
def test_robot_effect_named_first_and_recovered(spring_dict, case):
    label, make, declared, (lo, hi), key, param, truth, tol, factor = case
    value = draw(100 + sum(map(ord, label)), lo, hi)
    ex = explain(robot_data(spring_dict, make(value), declared), declared, max_steps=1)
    assert ex.steps, f"nothing found; verdict: {ex.verdict()}"
    step = ex.steps[0]
    assert step.effect == key, ex.verdict()
    k, backlash = spring_dict["k_Nm_per_rad"], spring_dict["actuator"]["backlash_rad"]
    p = step.after.parameters()[key][param]
    assert p["value"] == pytest.approx(truth(value, k, backlash), rel=tol)
    assert p["unit"] in ("rad", "1", "1/rad^2", "1/J", "rad/s", "s")
    assert step.before.errors["held_out"]["rmse"] / step.after.errors["held_out"]["rmse"] >= factor


def test_robot_clean_recording_adds_nothing(spring_dict):
    ex = explain(robot_data(spring_dict, {}, seed=5), ROBOT_DECLARED)
    assert ex.found == [], ex.verdict()
    assert ex.tests_after["white"]


def test_robot_two_undeclared_effects(spring_dict):
    ex = explain(robot_data(spring_dict, {"stiffness_scale": {"scale": 0.75}, "hall_offset": {"offset_rad": 0.02}}),
                 ROBOT_DECLARED, max_steps=3)
    assert set(ex.found) == {"stiffness_scale", "sensor_offset"}, ex.verdict()
    params = ex.final.parameters()
    assert params["stiffness_scale"]["scale"]["value"] == pytest.approx(0.75, rel=0.02)
    assert params["sensor_offset"]["offset"]["value"] == pytest.approx(0.02, rel=0.1)
