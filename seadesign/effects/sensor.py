"""Sensor effects: what a reading adds to the true value. Bound by default to `hall`.

Bind them to `motor`, `effort` or `deflection` for the other channels (the parameter's unit is
then the unit of that signal; the units below are for the default Hall binding). `EffortLag`
is the servo's current-based effort: a first-order lag of the torque it reports.
"""

from __future__ import annotations

import math

import numpy as np

from seadesign.constants import AS5600_BITS
from seadesign.effects.base import Effect, Param, Scales, Search, lowpass


class SensorOffset(Effect):
    """Constant offset: reading += c."""

    key = "sensor_offset"
    summary = "reading += c"
    signature = "mean shift"
    parameters = (Param("offset_rad", "rad", 0.02, -math.pi, math.pi, "offset c"),)
    writes = "hall"

    def _map(self, x, p, rng):
        return x["hall"] + p["offset_rad"]

    def search(self, s: Scales) -> Search:
        return {"offset_rad": (-s.measured_span, s.measured_span)}, [{"offset_rad": 0.0}]


class SensorDrift(Effect):
    """Linear drift: reading += r (t - t0), t0 the first sample time."""

    key = "sensor_drift"
    summary = "reading += r (t - t0)"
    signature = "ramp over the recording"
    parameters = (Param("rate_rad_per_s", "rad/s", 1e-4, -0.01, 0.01, "drift rate r"),)
    reads = ("time",)
    writes = "hall"
    stateful = True

    def _init(self, x, p):
        return {"t0": np.asarray(x["time"], dtype=float).copy()}

    def _advance(self, state, x, dt, p):
        return x["hall"] + p["rate_rad_per_s"] * (x["time"] - state["t0"])

    def _apply_stateful(self, x, p):
        return x["hall"] + p["rate_rad_per_s"] * (x["time"] - x["time"][..., :1])

    def search(self, s: Scales) -> Search:
        bound = 10.0 * s.measured_span / s.duration_s
        return {"rate_rad_per_s": (-bound, bound)}, [{"rate_rad_per_s": 0.0}]


class SensorStep(Effect):
    """A jump of the reading at one instant: reading += h for t >= t_j (a Hall sensor's level step).

    Several jumps are several instances. Unlike an offset (present from the start) or a drift (a
    ramp), it changes the reading at one unknown instant, which a fitter finds by change-point
    detection (`seadesign.calibration.changepoint`) and then holds fixed while it fits the size.
    """

    key = "sensor_step"
    summary = "reading += h for t >= t_j"
    signature = "level shift at one instant"
    parameters = (
        Param("time_s", "s", 0.0, 0.0, 1e9, "instant t_j of the jump (time from the recording's start)"),
        Param("size_rad", "rad", 0.05, -2 * math.pi, 2 * math.pi, "size h of the jump"),
    )
    reads = ("time",)
    writes = "hall"
    stateful = True  # needs the recording's start time

    def _init(self, x, p):
        return {"t0": np.asarray(x["time"], dtype=float).copy()}

    def _advance(self, state, x, dt, p):
        return x["hall"] + p["size_rad"] * (x["time"] - state["t0"] >= p["time_s"])

    def _apply_stateful(self, x, p):
        return x["hall"] + p["size_rad"] * (x["time"] - x["time"][..., :1] >= p["time_s"])

    def search(self, s: Scales) -> Search:
        return ({"time_s": (self.values["time_s"],) * 2, "size_rad": (-s.measured_span, s.measured_span)},
                [dict(self.values)])


class SensorDelay(Effect):
    """Pure delay: reading(t) = value(t - td), linear interpolation, held at the first value."""

    key = "sensor_delay"
    summary = "reading(t) = value(t - td)"
    signature = "residual about -td x rate; cross-correlation peak at a non-zero lag"
    parameters = (Param("delay_s", "s", 0.01, 0.0, 1.0, "delay td"),)
    reads = ("time",)
    writes = "hall"
    stateful = True

    def _init(self, x, p):
        return {"times": [], "values": []}

    def _advance(self, state, x, dt, p):
        t, v = float(np.max(x["time"])), x["hall"]
        state["times"].append(t)
        state["values"].append(np.asarray(v, dtype=float).copy())
        target = t - p["delay_s"]
        times = state["times"]
        while len(times) > 2 and times[1] <= target:  # keep one sample at or before the target
            times.pop(0)
            state["values"].pop(0)
        if target <= times[0] or len(times) == 1:
            return state["values"][0].copy()
        i = next(k for k in range(1, len(times)) if times[k] >= target)
        w = (target - times[i - 1]) / (times[i] - times[i - 1])
        return state["values"][i - 1] + w * (state["values"][i] - state["values"][i - 1])

    def _apply_stateful(self, x, p):
        t = np.broadcast_to(x["time"], x["hall"].shape)
        v = x["hall"]
        out = np.empty(v.shape)
        for idx in np.ndindex(v.shape[:-1]):
            out[idx] = np.interp(t[idx] - p["delay_s"], t[idx], v[idx])
        return out

    def search(self, s: Scales) -> Search:
        hi = min(1.0, 0.1 * s.duration_s)
        return {"delay_s": (-hi if s.generic else 0.0, hi)}, [{"delay_s": td} for td in (0.005, 0.03, 0.15)]


class SensorNoise(Effect):
    """White Gaussian noise: reading += N(0, std^2)."""

    key = "sensor_noise"
    summary = "reading += N(0, std^2)"
    parameters = (Param("std_rad", "rad", 0.002, 0.0, 1.0, "standard deviation"),)
    writes = "hall"
    random = True

    def _map(self, x, p, rng):
        return x["hall"] + rng.normal(0.0, p["std_rad"], size=np.shape(x["hall"]))


class Quantisation(Effect):
    """An n-bit angle encoder: reading = round(value / q) q with q = 2 pi / 2^n."""

    key = "quantisation"
    summary = "reading = round(value / q) q, q = 2 pi / 2^bits"
    parameters = (Param("bits", "bit", float(AS5600_BITS), 1.0, 32.0, "encoder resolution n per revolution"),)
    writes = "hall"

    def _map(self, x, p, rng):
        q = 2.0 * math.pi / 2.0 ** p["bits"]
        return np.round(x["hall"] / q) * q


class AngleWrap(Effect):
    """An absolute encoder's wrap-around: reading wrapped into [c - pi, c + pi)."""

    key = "angle_wrap"
    summary = "reading wrapped into [c - pi, c + pi)"
    parameters = (Param("centre_rad", "rad", 0.0, -math.pi, math.pi, "centre c of the output range"),)
    writes = "hall"

    def _map(self, x, p, rng):
        c = p["centre_rad"]
        return np.mod(x["hall"] - c + math.pi, 2.0 * math.pi) - math.pi + c


class EffortLag(Effect):
    """The servo's effort as a first-order lag of the torque it reports: effort' = (torque - effort) / te.

    The effort is computed from the motor current, which the servo filters; a lag te shows as
    structure against velocity in a model that reads the effort as the spring torque. Its inverse,
    torque = effort + te effort' (`torque_from_effort`), is what a model predicting from the effort uses.
    """

    key = "effort_lag"
    summary = "effort = lowpass(torque, te)"
    signature = "residual against velocity / torque rate; effort behind the spring torque"
    parameters = (Param("time_constant_s", "s", 0.02, 1e-4, 2.0, "time constant te of the lag"),)
    reads = ("time",)
    writes = "effort"
    stateful = True
    log_params = ("time_constant_s",)

    def _init(self, x, p):
        return {"y": np.asarray(x["effort"], dtype=float).copy()}

    def _advance(self, state, x, dt, p):
        state["y"] = state["y"] + (x["effort"] - state["y"]) * (1.0 - math.exp(-dt / p["time_constant_s"]))
        return state["y"].copy()

    def _apply_stateful(self, x, p):
        return lowpass(x["effort"], x["time"], p["time_constant_s"])

    @staticmethod
    def torque_from_effort(effort: np.ndarray, effort_rate: np.ndarray, time_constant_s: float) -> np.ndarray:
        """The torque (Nm) a lagged `effort` (Nm) reports, from its rate (Nm/s): effort + te effort'."""
        return effort + time_constant_s * effort_rate

    def search(self, s: Scales) -> Search:
        return ({"time_constant_s": (0.5 * s.dt_s, 1.0)},
                [{"time_constant_s": te} for te in (0.01, 0.05, 0.2)])
