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
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from seadesign.data import knee_channels
from seadesign.design.materials import Hyperelastic, Material, load_material
from seadesign.errors import ConfigError
from seadesign.design.spring import torque_curve
from seadesign.effects import DeadBand, Effect, Friction, spring_law
from seadesign.calibration.engine import SCALE, Explanation, TraceEntry
from seadesign.calibration.model import Fit
from seadesign.calibration.table import LoopData, LoopInputError, smooth_rate
from seadesign.calibration.terms import LAW_SHAPES
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
LAW_NOTE = ("an effective isotropic law of a printed part, which is anisotropic (layers, infill), fitted to the "
            "spring's torque against its rotation: it reproduces this part's curve, not a coupon's tensile test")
_MODULI = ("c10_Pa", "c01_Pa", "c20_Pa", "c30_Pa")


def fitted_law(material: Material, spring_modulus_Pa: float, fit: Fit) -> dict[str, Any]:
    """The material's finite-strain law fitted by the loop: every modulus (and 1 / compressibility) times the
    curve's stiffness scale relative to the modulus the spring was computed with, the law's shape from the fitted
    law-shape term when there is one (`loop.law_family`: Mooney-Rivlin's C01 share, Yeoh's C20 / C10, at the
    material's initial shear modulus). Parameters in Pa (1/Pa) with uncertainties and the correlation of the two
    fitted moduli (propagated from the fit's covariance), the initial shear modulus mu = 2 (C10 + C01) and the linear
    solve's Young's modulus that follows it. Exact for a torque curve: a hyperelastic law's stresses scale with its
    moduli when its compressibilities scale inversely, so the path's torque scales and its shape stays."""
    values = fit.parameters()
    scale = values.get(SCALE, {}).get("scale", {"value": 1.0, "uncertainty": 0.0})["value"]
    a = spring_modulus_Pa / material.youngs_modulus_Pa
    shape = next((t for t in fit.terms if t.key in LAW_SHAPES), None)
    fitted: list[tuple[tuple[str, str], float]] = [((SCALE, "scale"), scale)]
    if shape is None:
        def law_at(s: float, v: float) -> Hyperelastic:
            return material.scaled(a * s, "fitted").law
    else:
        param = shape.effect.parameters[0].name
        fitted.append(((shape.name, param), values[shape.name][param]["value"]))

        def law_at(s: float, v: float) -> Hyperelastic:
            return replace(material, hyperelastic=shape.effect.family.law(v)).scaled(a * s, "fitted").law
    x = np.array([v for _, v in fitted])
    cov = np.array([[fit.covariance.get((p, q), 0.0) for q, _ in fitted] for p, _ in fitted])
    if shape is None:
        x = np.append(x, 0.0)
        cov = np.pad(cov, ((0, 1), (0, 1)))
    law = law_at(*x)
    names = [n for n in _MODULI if getattr(law, n)] + ["mu_Pa"]

    def moduli(s: float, v: float) -> np.ndarray:
        m = law_at(s, v)
        return np.array([getattr(m, n) for n in names[:-1]] + [m.shear_modulus_Pa])

    jac = np.column_stack([(moduli(*(x + h)) - moduli(*(x - h))) / (2 * h[i])  # the moduli are linear in s and v
                           for i, h in enumerate(np.diag([1e-6 * max(abs(x[0]), 1.0), 1e-6]))])
    spread = jac @ cov @ jac.T
    sd = np.sqrt(np.clip(np.diag(spread), 0.0, None))
    out: dict[str, Any] = {"model": law.model, "factor_on_material_file": a * scale}
    for i, n in enumerate(names):
        out[n] = float(moduli(*x)[i])
        out[n.replace("_Pa", "_uncertainty_Pa")] = float(sd[i])
    out |= {n: getattr(law, n) for n in ("d1_per_Pa", "d2_per_Pa", "d3_per_Pa") if getattr(law, n)}
    if len(names) > 2:
        out[f"correlation_{names[0][:-3]}_{names[1][:-3]}"] = float(spread[0, 1] / max(sd[0] * sd[1], 1e-300))
    out["youngs_modulus_Pa"] = law_at(*x).shear_modulus_Pa * 2.0 * (1.0 + material.poisson_ratio)
    out["fitted"] = ["the curve's scale (one factor on every modulus)"] + \
        ([f"the law's shape, {shape.key} {shape.effect.parameters[0].name} = {fitted[1][1]:.4g} "
          f"({shape.effect.parameters[0].doc})"] if shape is not None else [])
    out["note"] = LAW_NOTE
    return out


def unsupported_shape(ex: Explanation) -> TraceEntry | None:
    """The best law-shape fit of the loop's last round when no shape was named (None: a shape was named, or none
    was traced)."""
    if any(t.key in LAW_SHAPES for t in ex.final.terms):
        return None
    return min((t for t in ex.last_trace if t.effect in LAW_SHAPES), key=lambda t: t.held_out_rmse, default=None)


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
            modulus = float(spring["material"]["youngs_modulus_Pa"])
            out["law"] = fitted_law(found, modulus, ex.final)
            free = unsupported_shape(ex)
            if free is not None:  # a shape the data cannot rule out widens what the modulus is known to
                shaped = fitted_law(found, modulus, free.fit)
                spread = abs(shaped["mu_Pa"] - out["law"]["mu_Pa"])
                out["law"]["mu_uncertainty_Pa"] = float(np.hypot(out["law"]["mu_uncertainty_Pa"], spread))
                gain = 1.0 - free.held_out_rmse / ex.final.errors["held_out"]["rmse"]
                out["law"]["shape_unsupported"] = {**{k: shaped[k] for k in shaped if k not in ("note", "fitted")},
                                                   "held_out_gain": gain, "fitted": shaped["fitted"]}
                out["law"]["fitted"].append(
                    f"the law's shape is not supported by the data (held-out gain {gain:.1%} with {free.effect}); "
                    f"with it free mu = {shaped['mu_Pa']:.4g} +- {shaped['mu_uncertainty_Pa']:.2g} Pa, so mu's "
                    f"uncertainty includes the difference, {spread:.2g} Pa")
    return out

