"""Effects in the torque path of the spring: deflection -> torque.

Order in a chain: dead zones act on `deflection` first, then `LinearSpring` turns it into
`torque`, then the torque effects add or scale.
"""

from __future__ import annotations

import math

import numpy as np

from seadesign.effects.base import Effect, Param, lowpass, rows, time_steps


class DeadBand(Effect):
    """Dead zone of total width b in the deflection: no torque while |deflection| < b/2.

    Used for the spring's own dead-band (fig. 5.5) and, as a second instance named
    `backlash`, for the gearbox backlash between motor and spring.
    """

    key = "dead_band"
    summary = "dead zone of total width b: deflection -> sign(d) max(|d| - b/2, 0)"
    parameters = (Param("width_rad", "rad", 0.01, 0.0, 0.5, "total width b of the dead zone"),)
    reads = ("deflection",)
    writes = "deflection"

    def _map(self, x, p, rng):
        d = x["deflection"]
        return np.sign(d) * np.maximum(np.abs(d) - 0.5 * p["width_rad"], 0.0)


class LinearSpring(Effect):
    """The SEA spring: torque += k * deflection."""

    key = "spring"
    summary = "linear torsion spring: torque += k d"
    parameters = (Param("k_Nm_per_rad", "Nm/rad", 9.106, 1e-3, 1e6, "torsional stiffness k"),)
    reads = ("deflection",)
    writes = "torque"

    def _map(self, x, p, rng):
        return x["torque"] + p["k_Nm_per_rad"] * x["deflection"]


class StiffnessScale(Effect):
    """Stiffness off by a factor (wrong modulus or infill): torque *= s."""

    key = "stiffness_scale"
    summary = "torque *= s (effective modulus or infill differs from the model)"
    parameters = (Param("scale", "1", 1.0, 0.01, 100.0, "ratio of true to modelled stiffness"),)
    writes = "torque"

    def _map(self, x, p, rng):
        return p["scale"] * x["torque"]


class CubicStiffening(Effect):
    """Odd cubic term: torque += k3 d^3 (k3 > 0 stiffening, k3 < 0 softening)."""

    key = "cubic_stiffening"
    summary = "torque += k3 d^3"
    parameters = (Param("k3_Nm_per_rad3", "Nm/rad^3", 2.0, -1e4, 1e4, "cubic stiffness coefficient"),)
    reads = ("deflection",)
    writes = "torque"

    def _map(self, x, p, rng):
        return x["torque"] + p["k3_Nm_per_rad3"] * x["deflection"] ** 3


class DahlHysteresis(Effect):
    """Rate-independent hysteresis (Dahl): torque += z, dz/dd = sigma (1 - z sign(d')/tau_h).

    z saturates at +-tau_h; the loop stays open at any rate. Discretised exactly for a
    monotonic deflection step: z -> s tau_h + (z - s tau_h) exp(-sigma |dd| / tau_h).
    """

    key = "hysteresis"
    summary = "Dahl hysteresis torque z with dz/dd = sigma (1 - z sign(dd)/tau_h)"
    parameters = (
        Param("torque_Nm", "Nm", 0.3, 1e-6, 20.0, "saturation torque tau_h of the hysteresis loop"),
        Param("stiffness_Nm_per_rad", "Nm/rad", 50.0, 1e-3, 1e5, "initial slope sigma after a reversal"),
    )
    reads = ("deflection",)
    writes = "torque"
    stateful = True

    def _init(self, x, p):
        return {"z": np.zeros_like(x["deflection"]), "d": x["deflection"].copy()}

    def _advance(self, state, x, dt, p):
        d = x["deflection"]
        step = d - state["d"]
        th = p["torque_Nm"]
        s = np.sign(step)
        state["z"] = s * th + (state["z"] - s * th) * np.exp(-p["stiffness_Nm_per_rad"] * np.abs(step) / th)
        state["d"] = d.copy()
        return x["torque"] + state["z"]

    def _apply_stateful(self, x, p):
        th, sig = p["torque_Nm"], p["stiffness_Nm_per_rad"]
        out = np.empty(np.broadcast_shapes(x["deflection"].shape, x["torque"].shape))
        flat = out.reshape(-1, out.shape[-1])
        for i, (ds, ts) in enumerate(rows(x["deflection"], x["torque"])):
            z, prev, zs = 0.0, ds[0], []
            for d, t in zip(ds, ts):
                step = d - prev
                s = (step > 0) - (step < 0)
                z = s * th + (z - s * th) * math.exp(-sig * abs(step) / th)
                prev = d
                zs.append(t + z)
            flat[i] = zs
        return out


class Viscoelastic(Effect):
    """Standard linear solid: a Maxwell arm (k2 with relaxation time tr) parallel to the spring.

    torque += k2 (d - d_r), d_r' = (d - d_r)/tr: stiffer for fast motion, a loop that vanishes
    at low and high frequency, relaxation under held load.
    """

    key = "viscoelastic"
    summary = "standard linear solid: torque += k2 (d - lowpass(d, tr))"
    parameters = (
        Param("maxwell_stiffness_Nm_per_rad", "Nm/rad", 3.0, 0.0, 1e5, "stiffness k2 of the Maxwell arm"),
        Param("relaxation_time_s", "s", 0.2, 1e-4, 1e4, "relaxation time tr = damper / k2"),
    )
    reads = ("deflection", "time")
    writes = "torque"
    stateful = True

    def _init(self, x, p):
        return {"relaxed": x["deflection"].copy()}

    def _advance(self, state, x, dt, p):
        d = x["deflection"]
        state["relaxed"] = state["relaxed"] + (d - state["relaxed"]) * (1.0 - math.exp(-dt / p["relaxation_time_s"]))
        return x["torque"] + p["maxwell_stiffness_Nm_per_rad"] * (d - state["relaxed"])

    def _apply_stateful(self, x, p):
        relaxed = lowpass(x["deflection"], x["time"], p["relaxation_time_s"])
        return x["torque"] + p["maxwell_stiffness_Nm_per_rad"] * (x["deflection"] - relaxed)


class ThermalSoftening(Effect):
    """Stiffness falls with temperature: torque *= 1 - a dT, dT driven by dissipated energy.

    dT' = eta |torque d'| / C - dT / tc  (a fraction eta of the mechanical power is lost as
    heat into a heat capacity C that cools with time constant tc). The factor is floored at
    0.05 so the spring never inverts.
    """

    key = "thermal_softening"
    summary = "torque *= 1 - a dT, C dT' = eta |torque d'| - C dT / tc"
    parameters = (
        Param("softening_per_K", "1/K", 0.01, 0.0, 0.05, "relative stiffness loss a per kelvin"),
        Param("loss_factor", "1", 0.1, 0.0, 1.0, "fraction eta of the mechanical power turned into heat"),
        Param("heat_capacity_J_per_K", "J/K", 15.0, 0.01, 1e4, "heat capacity C of the spring"),
        Param("cooling_time_s", "s", 600.0, 1.0, 1e6, "time constant tc of cooling to ambient"),
    )
    reads = ("deflection", "time")
    writes = "torque"
    stateful = True

    def _factor(self, dtemp, p):
        return np.maximum(1.0 - p["softening_per_K"] * dtemp, 0.05)

    def _init(self, x, p):
        return {"dtemp": np.zeros_like(x["deflection"]), "d": x["deflection"].copy()}

    def _advance(self, state, x, dt, p):
        d, tau = x["deflection"], x["torque"]
        heat = p["loss_factor"] * np.abs(tau * (d - state["d"])) / p["heat_capacity_J_per_K"]  # K gained this step
        decay = math.exp(-dt / p["cooling_time_s"])
        state["dtemp"] = state["dtemp"] * decay + heat
        state["d"] = d.copy()
        return tau * self._factor(state["dtemp"], p)

    def _apply_stateful(self, x, p):
        a, eta, cap, tc = (p[k] for k in ("softening_per_K", "loss_factor", "heat_capacity_J_per_K", "cooling_time_s"))
        out = np.empty(np.broadcast_shapes(x["deflection"].shape, x["torque"].shape))
        flat = out.reshape(-1, out.shape[-1])
        for i, (ds, ts, dts) in enumerate(rows(x["deflection"], x["torque"], time_steps(x["time"]))):
            dtemp, prev, ys = 0.0, ds[0], []
            for d, t, dt in zip(ds, ts, dts):
                dtemp = dtemp * math.exp(-dt / tc) + eta * abs(t * (d - prev)) / cap
                prev = d
                ys.append(t * max(1.0 - a * dtemp, 0.05))
            flat[i] = ys
        return out


class TemperatureSoftening(Effect):
    """Stiffness falls with a measured temperature: torque *= 1 - a (T - T0), floored at 0.05."""

    key = "temperature_softening"
    summary = "torque *= 1 - a (T - T0) from a measured temperature"
    parameters = (
        Param("softening_per_K", "1/K", 0.01, 0.0, 0.05, "relative stiffness loss a per kelvin"),
        Param("reference_temperature_C", "degC", 23.0, -40.0, 150.0, "temperature T0 at which k holds"),
    )
    reads = ("temperature",)
    writes = "torque"

    def _map(self, x, p, rng):
        factor = 1.0 - p["softening_per_K"] * (x["temperature"] - p["reference_temperature_C"])
        return x["torque"] * np.maximum(factor, 0.05)
