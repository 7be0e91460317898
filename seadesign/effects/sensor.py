"""Sensor effects: what a reading adds to the true value. Bound by default to `hall`.

Bind them to `motor` or `effort` for the other channels (the parameter's unit is then the
unit of that signal; the units below are for the default Hall binding).
"""

from __future__ import annotations

import math

import numpy as np

from seadesign.effects.base import Effect, Param


class SensorOffset(Effect):
    """Constant offset: reading += c."""

    key = "sensor_offset"
    summary = "reading += c"
    parameters = (Param("offset_rad", "rad", 0.02, -math.pi, math.pi, "offset c"),)
    writes = "hall"

    def _map(self, x, p, rng):
        return x["hall"] + p["offset_rad"]


class SensorDrift(Effect):
    """Linear drift: reading += r (t - t0), t0 the first sample time."""

    key = "sensor_drift"
    summary = "reading += r (t - t0)"
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


class SensorDelay(Effect):
    """Pure delay: reading(t) = value(t - td), linear interpolation, held at the first value."""

    key = "sensor_delay"
    summary = "reading(t) = value(t - td)"
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
    parameters = (Param("bits", "bit", 12.0, 1.0, 32.0, "encoder resolution n per revolution"),)
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
