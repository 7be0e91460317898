"""The loop's goal cases: robot-format recordings with one effect drawn from a seeded range (see
`test_calibration_goal.py` for the protocol), written by `helpers_generators.robot`, apart from the simulator."""

from __future__ import annotations

import numpy as np

from helpers_generators import robot

# case -> (library key, declared name or None, parameter, range, fixed parameters, relative tolerance, length s);
# tolerances about three times the worst error over the three draws: backlash 0.018, gear friction 0.0075,
# delay 0.0029, step 0.0034, thermal softening 0.093
GOAL = {
    "backlash": ("dead_band", "backlash", "width_rad", (0.02, 0.05), {}, 0.05, 60.0),
    "gear_friction": ("friction", "gear_friction", "coulomb_Nm", (0.2, 0.5), {"viscous_Nm_s_per_rad": 0.0}, 0.022, 60.0),
    "sensor_delay": ("sensor_delay", None, "delay_s", (0.02, 0.06), {}, 0.009, 60.0),
    "sensor_step": ("sensor_step", None, "size_rad", (0.03, 0.15), {}, 0.01, 60.0),
    "thermal_softening": ("thermal_softening", None, "softening_per_J", (0.012, 0.016), {"cooling_time_s": 300.0},
                          0.3, 120.0),
    "none": (None, None, None, None, {}, None, 60.0),
}


def goal_recording(case: str, draw_index: int):
    """(recording, the drawn parameter value or None) of a goal case's draw."""
    key, _, param, bounds, fixed, _, duration = GOAL[case]
    rng = np.random.default_rng([draw_index, sum(map(ord, case)), 5])
    effects, value = {}, None
    if key:
        value = float(rng.uniform(*bounds))
        effects = {key: {param: value, **fixed}}
        if key == "sensor_step":
            effects[key]["time_s"] = round(float(rng.uniform(0.2, 0.8)) * duration, 2)
    return robot(effects, seed=40 + draw_index, duration_s=duration), value
