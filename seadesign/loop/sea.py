"""SEA adapters: a bench file or a robot recording plus a spring.json -> `LoopData` and the declared
effects, and the calibration that flows back into the design.

The spring is spring.json's k (`LinearSpring`), or its large-deflection `torque_curve` when it carries
one (`SpringCurve`, PCHIP): the model's spring either way, its stiffness scale always refitted.

- Bench, `torque` (default): measured torque_Nm from the deflection_rad reading (stiffness direction;
  sensor effects act on the deflection reading); signals time, deflection, temperature when present.
- Bench, `deflection`: measured deflection_rad from torque_Nm (compliance direction); the bench's friction
  acts against the deflection rate.
- Robot, one knee (flexion positive, the right knee un-mirrored, `seadesign.data.knee_channels`):
  measured Hall angle = motor angle - deflection, the deflection from the effort through the
  declared effects (compliance direction): gear friction on the motor side taken off the effort, the
  spring inverted, the gearbox backlash as free travel. Declared by default (`robot_declared`):
  `backlash` (the actuator's, from spring.json) and `gear_friction` (Coulomb, `GEAR_COULOMB_NM`).
"""

from __future__ import annotations

import hashlib
from pathlib import Path
from typing import Any

import pandas as pd

from seadesign.data import knee_channels
from seadesign.design.materials import Material, load_material
from seadesign.errors import ConfigError
from seadesign.design.spring import torque_curve
from seadesign.effects import DeadBand, Effect, Friction, spring_law
from seadesign.loop.engine import Explanation
from seadesign.loop.table import LoopData, LoopInputError, smooth_rate
from seadesign.twin.config import GEAR_COULOMB_NM

#: the robot model's declared effects: library key -> name in the model
ROBOT_DECLARED = {"dead_band": "backlash", "friction": "gear_friction"}


def robot_declared(spring: dict[str, Any], keys: tuple[str, ...] = tuple(ROBOT_DECLARED)) -> list[Effect]:
    """The declared effects of the robot model (library keys `dead_band`, `friction`), valued from spring.json."""
    unknown = set(keys) - set(ROBOT_DECLARED)
    if unknown:
        raise LoopInputError(f"a robot model declares only {', '.join(ROBOT_DECLARED)}; not {', '.join(sorted(unknown))}")
    out: list[Effect] = []
    if "dead_band" in keys:
        out.append(DeadBand("backlash", width_rad=float(spring["actuator"]["backlash_rad"])))
    if "friction" in keys:
        out.append(Friction("gear_friction", bind={"velocity": "motor_velocity", "load_torque": "effort"},
                            coulomb_Nm=GEAR_COULOMB_NM, viscous_Nm_s_per_rad=0.0))
    return out


def bench_loop_data(df: pd.DataFrame, spring: dict[str, Any], predict: str = "torque") -> LoopData:
    """LoopData of a bench table (`read_bench`) with the spring of spring.json; `predict` torque or deflection."""
    time, torque, defl = (df[c].to_numpy(float) for c in ("time_s", "torque_Nm", "deflection_rad"))
    signals = {"time": time}
    units = {"time": "s", "deflection": "rad", "temperature": "degC", "torque": "Nm", "velocity": "rad/s"}
    columns = {"time": "time_s"}
    if "temperature_C" in df.columns:
        signals["temperature"] = df["temperature_C"].to_numpy(float)
        columns["temperature"] = "temperature_C"
    if predict == "torque":
        return LoopData(torque, {**signals, "deflection": defl}, "stiffness", spring=spring_law(float(spring["k_Nm_per_rad"]), torque_curve(spring)),
                        sensor_on="deflection", measured_name="torque_Nm", measured_unit="Nm", units=units,
                        columns={**columns, "deflection": "deflection_rad", "measured": "torque_Nm"})
    if predict == "deflection":
        # the bench's friction acts against the deflection rate: from the reading (the torque's rate would carry the
        # friction's own jump); a Savitzky-Golay derivative, whose kernel leaves out the sample itself
        rate = smooth_rate(defl, time)
        return LoopData(defl, {**signals, "torque": torque, "velocity": rate}, "compliance", spring=spring_law(float(spring["k_Nm_per_rad"]), torque_curve(spring)),
                        measured_name="deflection_rad", measured_unit="rad", units=units,
                        columns={**columns, "torque": "torque_Nm", "measured": "deflection_rad",
                                 "velocity": "d(deflection_rad)/dt"})
    raise LoopInputError(f"predict = '{predict}': use 'torque' (from deflection) or 'deflection' (from torque)")


def robot_loop_data(df: pd.DataFrame, spring: dict[str, Any], knee: str = "l") -> LoopData:
    """LoopData of one knee of a robot recording (`read_recording`, optionally cleaned)."""
    ch = knee_channels(df, knee)
    return LoopData(
        ch["hall"], {"time": df["time_s"].to_numpy(float), "motor": ch["motor"], "motor_velocity": ch["motor_velocity"],
                     "effort": ch["effort"]},
        "compliance", spring=spring_law(float(spring["k_Nm_per_rad"]), torque_curve(spring)), base=ch["motor"], sign=-1.0,
        measured_name=ch.columns["hall"], measured_unit="rad",
        units={"time": "s", "motor": "rad", "motor_velocity": "rad/s", "effort": "Nm"},
        columns={"measured": ch.columns["hall"], "time": "time_s",
                 **{r: ch.columns[r] for r in ("motor", "motor_velocity", "effort")}})


#: what the fitted law is, said with every calibration
LAW_NOTE = ("an effective isotropic law of a printed part, which is anisotropic (layers, infill): one factor on "
            "every modulus of the material's law, fitted to the spring's torque against its rotation")


def fitted_law(material: Material, spring_modulus_Pa: float, scale: float, scale_uncertainty: float) -> dict[str, Any]:
    """The material's finite-strain law with every modulus (and 1 / compressibility) times the fitted stiffness
    scale, relative to the modulus the spring was computed with: parameters (Pa, 1/Pa) with uncertainties and
    the initial shear modulus mu = 2 (C10 + C01). Exact for a torque curve: a hyperelastic law's stresses scale
    with its moduli when its compressibilities scale inversely, so the path's torque scales and its shape stays."""
    factor = spring_modulus_Pa * scale / material.youngs_modulus_Pa
    fitted = material.scaled(factor, "fitted")
    law = fitted.law
    relative = scale_uncertainty / scale
    out: dict[str, Any] = {"model": law.model, "factor_on_material_file": factor}
    for name in ("c10_Pa", "c01_Pa", "c20_Pa", "c30_Pa"):
        if getattr(law, name):
            out[name], out[name.replace("_Pa", "_uncertainty_Pa")] = getattr(law, name), getattr(law, name) * relative
    out |= {name: getattr(law, name) for name in ("d1_per_Pa", "d2_per_Pa", "d3_per_Pa") if getattr(law, name)}
    out["mu_Pa"] = law.shear_modulus_Pa
    out["mu_uncertainty_Pa"] = out["mu_Pa"] * relative
    out["youngs_modulus_Pa"] = fitted.youngs_modulus_Pa  # the linear solve's, following mu
    out["fitted"] = ["one factor on every modulus (the curve's scale)"]
    out["note"] = LAW_NOTE
    return out


def calibration(ex: Explanation, spring: dict[str, Any], source: Path,
                material: Material | None = None) -> dict[str, Any]:
    """The calibration JSON for `seadesign sweep --calibration`: `stiffness_scale` (fitted k / model k; the
    fitted value whether or not it differs significantly), the material calibrated and its fitted law
    (`fitted_law`: the spring's material, found by its name, unless `material` is given: the fitted modulus
    expressed as that material's law), the measured file `source` and its SHA-256, and every fitted parameter with
    unit and uncertainty."""
    params = ex.final.parameters()
    k = float(spring["k_Nm_per_rad"])
    scale = params.get("stiffness_scale", {}).get("scale", {"value": 1.0, "uncertainty": 0.0})
    out: dict[str, Any] = {
        "stiffness_scale": scale["value"],
        "stiffness_scale_uncertainty": scale["uncertainty"],
        "stiffness_scale_correlated_with": scale.get("correlated_with", {}),
        "k_model_Nm_per_rad": k,
        "k_fitted_Nm_per_rad": k * scale["value"],
        "source": str(source),
        "source_sha256": hashlib.sha256(Path(source).read_bytes()).hexdigest(),
        "effects_found": ex.found,
        "declared": [{"name": c.name, "effect": c.key, "declared": c.declared, "supported": c.supported,
                      "fitted": c.fitted} for c in ex.declared],
        "parameters": params,
        "held_out_rmse_before": ex.plain.errors["held_out"]["rmse"],
        "held_out_rmse_after": ex.final.errors["held_out"]["rmse"],
        "rmse_unit": ex.data.measured_unit,
    }
    modelled = spring.get("material") or {}
    if "youngs_modulus_Pa" in modelled:
        out["youngs_modulus_model_Pa"] = modelled["youngs_modulus_Pa"]
        out["youngs_modulus_fitted_Pa"] = modelled["youngs_modulus_Pa"] * scale["value"]
        found = material
        if found is None:
            try:
                found = load_material(spring["material"]["name"])
            except (ConfigError, KeyError):  # a material not on this machine: the modulus alone
                found = None
        if found is not None:
            out["material"] = found.key
            out["law"] = fitted_law(found, float(spring["material"]["youngs_modulus_Pa"]), scale["value"],
                                    scale["uncertainty"])
    return out

