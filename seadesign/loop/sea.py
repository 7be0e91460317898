"""SEA adapters: a bench file or a robot recording plus a spring.json -> `LoopData`, and the
calibration that flows back into the design.

- Bench, `torque` (default): measured torque_Nm, predicted k x deflection_rad (path term, stiffness
  direction); signals time, displacement (deflection), temperature when the file has it.
- Bench, `deflection`: measured deflection_rad, predicted torque_Nm / k (compliance direction).
- Robot, one knee (flexion positive, the right knee un-mirrored): measured Hall angle, predicted
  motor angle minus the deflection the effort implies through the simulator's declared chain
  (gear friction taken off the effort, the spring, the gearbox backlash as free travel):
  hall = motor - (effort - gear friction(motor velocity)) / k - sign(.) backlash / 2.
  Declared effects (not traced) by default: `dead_band` (backlash) and `friction` (gear
  friction); signals time, displacement (spring deflection), velocity (motor), torque (spring).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pandas as pd

from seadesign.data import KNEE_SIGN
from seadesign.loop.engine import Explanation
from seadesign.loop.table import LoopData, LoopInputError
from seadesign.twin import KneeConfig, knee_effects

ROBOT_DECLARED = ("dead_band", "friction")


def bench_loop_data(df: pd.DataFrame, spring: dict[str, Any], predict: str = "torque") -> LoopData:
    """LoopData of a bench table (`read_bench`) with k from spring.json; `predict` torque or deflection."""
    k = float(spring["k_Nm_per_rad"])
    time, torque, defl = (df[c].to_numpy(float) for c in ("time_s", "torque_Nm", "deflection_rad"))
    signals = {"time": time}
    units = {"time": "s", "displacement": "rad", "temperature": "degC"}
    columns = {"time": "time_s"}
    if "temperature_C" in df.columns:
        signals["temperature"] = df["temperature_C"].to_numpy(float)
        columns["temperature"] = "temperature_C"
    if predict == "torque":
        return LoopData(torque, k * defl, {**signals, "displacement": defl}, measured_name="torque_Nm",
                        measured_unit="Nm", units=units, columns={**columns, "displacement": "deflection_rad",
                                                                  "measured": "torque_Nm"}, gain=k)
    if predict == "deflection":
        return LoopData(defl, torque / k, {**signals, "displacement": torque / k, "torque": torque},
                        measured_name="deflection_rad", measured_unit="rad", units={**units, "torque": "Nm"},
                        columns={**columns, "displacement": "torque_Nm / k", "measured": "deflection_rad",
                                 "torque": "torque_Nm"},
                        gain=1.0, direction="compliance")
    raise LoopInputError(f"predict = '{predict}': use 'torque' (from deflection) or 'deflection' (from torque)")


def robot_loop_data(df: pd.DataFrame, spring: dict[str, Any], knee: str = "l",
                    declared: tuple[str, ...] = ROBOT_DECLARED) -> LoopData:
    """LoopData of one knee of a robot recording (`read_recording`, optionally cleaned).

    The prediction holds the simulator's gear friction only when `friction` is declared and its
    backlash only when `dead_band` is; undeclared, they are left for the loop to find.
    """
    if knee not in KNEE_SIGN:
        raise LoopInputError(f"knee '{knee}' is unknown; use one of {', '.join(KNEE_SIGN)}")
    need = [f"{knee}_{f}" for f in ("knee_pos", "hall_pos", "knee_vel", "knee_eff")] + ["time_s"]
    missing = [c for c in need if c not in df.columns]
    if missing:
        raise LoopInputError(f"the recording lacks column(s) {', '.join(missing)}; read it with read_recording")
    s = KNEE_SIGN[knee]
    k = float(spring["k_Nm_per_rad"])
    chain = knee_effects(KneeConfig.from_spring(spring))
    motor, hall = s * df[f"{knee}_knee_pos"].to_numpy(float), s * df[f"{knee}_hall_pos"].to_numpy(float)
    vm, effort = s * df[f"{knee}_knee_vel"].to_numpy(float), s * df[f"{knee}_knee_eff"].to_numpy(float)
    torque, torque_col = effort, f"{knee}_knee_eff"
    if "friction" in declared:
        torque = effort - chain["gear_friction"].apply({"motor_velocity": vm, "effort": np.zeros_like(vm)})
        torque_col = f"{knee}_knee_eff - gear friction"
    spring_defl = torque / k
    backlash = chain["backlash"].values["width_rad"] if "dead_band" in declared else 0.0
    defl = spring_defl + np.sign(spring_defl) * 0.5 * backlash
    return LoopData(
        hall, motor - defl,
        {"time": df["time_s"].to_numpy(float), "displacement": spring_defl, "velocity": vm, "torque": torque},
        measured_name=f"{knee}_hall_pos", measured_unit="rad",
        units={"time": "s", "displacement": "rad", "velocity": "rad/s", "torque": "Nm"},
        columns={"measured": f"{knee}_hall_pos", "predicted": f"{knee}_knee_pos - deflection({knee}_knee_eff)",
                 "time": "time_s", "displacement": f"({torque_col}) / k", "velocity": f"{knee}_knee_vel",
                 "torque": torque_col},
        path=-defl, gain=-1.0, direction="compliance")


def calibration(ex: Explanation, spring: dict[str, Any], source: str) -> dict[str, Any]:
    """The calibration JSON for `seadesign sweep --calibration`: `stiffness_scale` (fitted k / model k,
    1 when the loop found no stiffness error) plus every fitted parameter with unit and uncertainty."""
    params = ex.final.parameters()
    k = float(spring["k_Nm_per_rad"])
    scale = params.get("stiffness_scale", {}).get("scale", {"value": 1.0, "uncertainty": 0.0})
    out: dict[str, Any] = {
        "stiffness_scale": scale["value"],
        "stiffness_scale_uncertainty": scale["uncertainty"],
        "k_model_Nm_per_rad": k,
        "k_fitted_Nm_per_rad": k * scale["value"],
        "source": source,
        "effects_found": ex.found,
        "parameters": params,
        "held_out_rmse_before": ex.plain.errors["held_out"]["rmse"],
        "held_out_rmse_after": ex.final.errors["held_out"]["rmse"],
        "rmse_unit": ex.data.measured_unit,
    }
    material = spring.get("material") or {}
    if "youngs_modulus_Pa" in material:
        out["youngs_modulus_model_Pa"] = material["youngs_modulus_Pa"]
        out["youngs_modulus_fitted_Pa"] = material["youngs_modulus_Pa"] * scale["value"]
    return out
