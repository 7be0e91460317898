"""Sensor effects: what a reading adds to the true value. Bound by default to `hall`.

Bind them to `motor`, `effort` or `deflection` for the other channels (the parameter's unit is
then the unit of that signal; the units below are for the default Hall binding). `EffortLag`
is the servo's current-based effort: a first-order lag of the torque it reports.
"""

from __future__ import annotations

import math

import numpy as np

from seadesign.constants import AS5600_BITS
from seadesign.effects.base import EXACT, Effect, Param, Scales, Search, lowpass


class SensorOffset(Effect):
    """Constant offset: reading += c."""

    key = "sensor_offset"
    summary = "reading += c"
    signature = "mean shift"
    parameters = (Param("offset_rad", "rad", 0.02, -math.pi, math.pi, "offset c"),)
    writes = "hall"

    def _map(self, x, p, rng, xp=np, options=EXACT):
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

    def _init(self, x, p, xp=np):
        return {"t0": x["time"]}

    def _advance(self, state, x, dt, p, xp=np, options=EXACT):
        return x["hall"] + p["rate_rad_per_s"] * (x["time"] - state["t0"]), state

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

    def _init(self, x, p, xp=np):
        return {"t0": x["time"]}

    def _advance(self, state, x, dt, p, xp=np, options=EXACT):
        jumped = xp.astype(x["time"] - state["t0"] >= p["time_s"], x["hall"].dtype)
        return x["hall"] + p["size_rad"] * jumped, state

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

    def _init(self, x, p, xp=np):
        return {"times": (), "values": ()}  # the samples since the last one at or before t - td

    def _advance(self, state, x, dt, p, xp=np, options=EXACT):
        t = float(xp.max(x["time"]))
        times, values = (*state["times"], t), (*state["values"], x["hall"])
        target = t - p["delay_s"]
        first = 0
        while len(times) - first > 2 and times[first + 1] <= target:  # keep one sample at or before the target
            first += 1
        times, values = times[first:], values[first:]
        kept = {"times": times, "values": values}
        if target <= times[0] or len(times) == 1:
            return values[0], kept
        i = next(k for k in range(1, len(times)) if times[k] >= target)
        w = (target - times[i - 1]) / (times[i] - times[i - 1])
        return values[i - 1] + w * (values[i] - values[i - 1]), kept

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

    def _map(self, x, p, rng, xp=np, options=EXACT):
        if not options.noise:
            return x["hall"]
        return x["hall"] + p["std_rad"] * rng.standard_normal(tuple(x["hall"].shape))


class Quantisation(Effect):
    """An n-bit angle encoder: reading = round(value / q) q with q = 2 pi / 2^n."""

    key = "quantisation"
    summary = "reading = round(value / q) q, q = 2 pi / 2^bits"
    parameters = (Param("bits", "bit", float(AS5600_BITS), 1.0, 32.0, "encoder resolution n per revolution"),)
    writes = "hall"

    def _map(self, x, p, rng, xp=np, options=EXACT):
        v = x["hall"]
        if not options.quantise:
            return v
        q = 2.0 * math.pi / 2.0 ** p["bits"]
        rounded = xp.round(v / q) * q
        return rounded if options.stop_gradient is None else v + options.stop_gradient(rounded - v)


class AngleWrap(Effect):
    """An absolute encoder's wrap-around: reading wrapped into [c - pi, c + pi)."""

    key = "angle_wrap"
    summary = "reading wrapped into [c - pi, c + pi)"
    parameters = (Param("centre_rad", "rad", 0.0, -math.pi, math.pi, "centre c of the output range"),)
    writes = "hall"

    def _map(self, x, p, rng, xp=np, options=EXACT):
        c = p["centre_rad"]
        return xp.remainder(x["hall"] - c + math.pi, 2.0 * math.pi) - math.pi + c


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

    def _init(self, x, p, xp=np):
        return {"y": x["effort"]}

    def _advance(self, state, x, dt, p, xp=np, options=EXACT):
        y = state["y"] + (x["effort"] - state["y"]) * (1.0 - math.exp(-dt / p["time_constant_s"]))
        return y, {"y": y}

    def _apply_stateful(self, x, p):
        return lowpass(x["effort"], x["time"], p["time_constant_s"])

    @staticmethod
    def torque_from_effort(effort: np.ndarray, effort_rate: np.ndarray, time_constant_s: float) -> np.ndarray:
        """The torque (Nm) a lagged `effort` (Nm) reports, from its rate (Nm/s): effort + te effort'."""
        return effort + time_constant_s * effort_rate

    def search(self, s: Scales) -> Search:
        return ({"time_constant_s": (0.5 * s.dt_s, 1.0)},
                [{"time_constant_s": te} for te in (0.01, 0.05, 0.2)])
