"""The loop's input: a measured column, the signals that drive the model, and how the model is built.

Signals use the one vocabulary of the effect library (`seadesign.effects.SIGNALS`): `time`,
`deflection`, `torque`, `velocity`, `angle`, `motor`, `motor_velocity`, `effort`, `temperature`,
`energy`. Two directions:

- `stiffness`: the measured quantity is a torque (or force) the model computes from a `deflection`
  (or position). A generic table gives the model's prediction column (`predicted`), whose slope
  against the deflection (`gain`) is estimated; a bench test gives the spring (`spring`: linear k or
  the large-deflection curve) and the model is spring(deflection). `sensor_on="deflection"` (bench):
  sensor effects act on the deflection reading; otherwise on the measured column.
- `compliance`: the measured quantity is an angle: `base + sign x deflection`, the deflection computed
  from a torque through the spring's inverse (bench: measured deflection from `torque`, base 0,
  sign +1; robot: Hall = `motor` - deflection from the `effort`, sign -1). Needs `spring`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import lru_cache
from typing import Any

import numpy as np
import pandas as pd
from scipy.ndimage import convolve1d
from scipy.signal import savgol_coeffs, savgol_filter

from seadesign.effects import SIGNALS, CurveRangeError, Effect, Scales
from seadesign.errors import DataError

#: the signals the loop reads (a subset of the effect library's vocabulary) -> meaning (unit)
ROLES: dict[str, str] = {k: f"{SIGNALS[k][1]} ({SIGNALS[k][0]})" for k in
                         ("time", "deflection", "torque", "velocity", "angle", "motor", "motor_velocity", "effort",
                          "temperature", "energy")}
ROLES["deflection"] = "deflection or position driving the model (rad, or m on a linear machine)"
ROLES["velocity"] = "rate of the deflection or position (rad/s or m/s); computed when absent"
DIRECTIONS = ("stiffness", "compliance")


#: the least share of a record's samples that must lie on the spring's torque curve
MIN_IN_RANGE = 0.5


class LoopInputError(DataError):
    """The loop's table, columns or roles are unusable (the message names the column and the fix)."""


@dataclass(frozen=True)
class CurveCoverage:
    """Samples whose measured deflection goes past the end of the spring's torque curve: left out of the fit."""

    excluded: int
    samples: int
    end_rotation_rad: float
    end_torque_Nm: float
    stop_reason: str  # why the curve ends (the path's stop)
    max_deflection_rad: float  # the largest measured |deflection|
    first_time_s: float  # when the measurement first leaves the curve

    def text(self) -> str:
        """What was left out and what it means."""
        return (f"{self.excluded} of {self.samples} samples ({self.excluded / self.samples:.1%}) lie past the end of "
                f"the spring's torque curve and are left out of the fit and its errors: the measured deflection "
                f"reaches {self.max_deflection_rad:.4g} rad (first at {self.first_time_s:.4g} s), the curve ends at "
                f"{self.end_rotation_rad:.4g} rad, {self.end_torque_Nm:.4g} Nm (stop reason '{self.stop_reason}'). "
                "The measurement went where the model does not follow; a part that carries load smoothly past a "
                "predicted end is evidence against that end (a path that stopped at a bifurcation, an "
                "unconverged step or a limit point the printed part does not show).")


@dataclass
class LoopData:
    """Arrays of one experiment, time-ordered; units per signal in `units` and for the measured column."""

    measured: np.ndarray
    signals: dict[str, np.ndarray]
    direction: str = "stiffness"
    predicted: np.ndarray | None = None
    spring: Effect | None = None
    base: np.ndarray | None = None
    sign: float = 1.0
    sensor_on: str = "measured"
    measured_name: str = "measured"
    measured_unit: str = "1"
    units: dict[str, str] = field(default_factory=dict)
    columns: dict[str, str] = field(default_factory=dict)
    gain: float | None = None
    shapes: dict[str, Effect] = field(default_factory=dict)  # law-shape candidates (`terms.LAW_SHAPES`) by key
    notes: list[str] = field(default_factory=list)  # what the verdict must also say about the data (coverage)
    in_range: np.ndarray = field(init=False, repr=False)  # samples the model covers (the fit and its errors use these)
    coverage: "CurveCoverage | None" = field(init=False, default=None)  # where the data leave the torque curve

    def __post_init__(self) -> None:
        self.measured = np.asarray(self.measured, dtype=float)
        n = self.measured.size
        if n < 50:
            raise LoopInputError(f"the table has {n} rows; the loop needs at least 50 time-ordered samples")
        unknown = set(self.signals) - set(ROLES)
        if unknown:
            raise LoopInputError(f"unknown signal role(s) {sorted(unknown)}; roles are: {', '.join(ROLES)}")
        if self.direction not in DIRECTIONS:
            raise LoopInputError(f"direction '{self.direction}' is unknown; use one of {', '.join(DIRECTIONS)}")
        for role, values in list(self.signals.items()):
            values = np.asarray(values, dtype=float)
            if values.shape != (n,):
                raise LoopInputError(f"signal '{role}' has {values.size} values, the measured column {n}")
            self.signals[role] = values
        if self.predicted is not None:
            self.predicted = np.asarray(self.predicted, dtype=float)
            if self.predicted.shape != (n,):
                raise LoopInputError("measured and predicted columns differ in length")
        arrays = [(self.measured_name, self.measured), *self.signals.items()]
        for name, values in arrays + ([("predicted", self.predicted)] if self.predicted is not None else []):
            bad = np.flatnonzero(~np.isfinite(values))
            if bad.size:
                raise LoopInputError(f"column '{self.columns.get(name, name)}' is not finite at row {int(bad[0])}; "
                                     "drop or interpolate such rows first")
        if "time" not in self.signals:
            self.signals["time"] = np.arange(n, dtype=float)
            self.units["time"] = "sample"
        if np.any(np.diff(self.signals["time"]) <= 0):
            raise LoopInputError(f"time column '{self.columns.get('time', 'time')}' must strictly increase")
        if "velocity" not in self.signals and "deflection" in self.signals:
            self.signals["velocity"] = smooth_rate(self.signals["deflection"], self.signals["time"])
            self.units["velocity"] = f"{self.units.get('deflection', '1')}/s"
            self.columns["velocity"] = f"d({self.columns.get('deflection', 'deflection')})/dt"
        if self.direction == "compliance" and (self.spring is None or not ({"torque", "effort"} & set(self.signals))):
            raise LoopInputError("the compliance direction needs a spring and a torque or effort signal")
        if self.predicted is None and (self.spring is None or "deflection" not in self.signals) \
                and self.direction == "stiffness":
            raise LoopInputError("a table needs a predicted column, or a spring and a deflection signal")
        if self.gain is None:
            self.gain = self._gain()
        self.in_range = np.ones(n, bool)
        if hasattr(self.spring, "curve"):
            self._cover(self.spring.curve)

    def _cover(self, curve) -> None:
        """Leave out the samples whose measured deflection lies past the torque curve's end (nothing is
        extrapolated), and evaluate the curve clamped for a fitter's trial values; a record of which fewer than
        `MIN_IN_RANGE` lie on the curve is a CurveRangeError."""
        if self.direction == "compliance":
            deflection = self.sign * (self.measured - (0.0 if self.base is None else self.base))
        else:
            deflection = self.signals["deflection"]
        deflection = np.abs(self.smoothed(deflection))
        self.spring = self.spring.replace(clamp=True)
        if curve.hard_stop:  # the stop carries the rest: every sample is on the model
            return
        self.in_range = deflection <= curve.end_rotation_rad
        n_in = int(self.in_range.sum())
        if n_in < MIN_IN_RANGE * self.n:
            raise CurveRangeError(
                f"{self.n - n_in} of {self.n} samples ({1 - n_in / self.n:.0%}) are past the spring's torque curve, "
                f"which covers deflections up to {curve.end_rotation_rad:.4g} rad ({curve.end_torque_Nm:.4g} Nm; it "
                f"ends with stop reason '{curve.stop_reason}'); the measured deflection reaches "
                f"{deflection.max():.4g} rad. The loop needs at least {MIN_IN_RANGE:.0%} of the record on the model: "
                "compute the curve further, or test over the range it covers")
        if n_in < self.n:
            out = ~self.in_range
            self.coverage = CurveCoverage(int(out.sum()), self.n, curve.end_rotation_rad, curve.end_torque_Nm,
                                          curve.stop_reason, float(deflection[out].max()),
                                          float(self.time[np.flatnonzero(out)[0]]))

    def _gain(self) -> float:
        """Slope of the spring path against the deflection (measured unit per deflection unit)."""
        if self.spring is not None:
            return spring_slope(self.spring)
        if "deflection" not in self.signals:
            return 1.0
        d = self.signals["deflection"]
        return float(d @ self.predicted / max(d @ d, 1e-300))

    def smooth(self, role: str) -> np.ndarray:
        """Signal `role` through a quadratic Savitzky-Golay smoother (~0.1 s), cached: the input of
        stateful effects, so sensor noise does not act as many tiny reversals."""
        key = f"_smooth_{role}"
        if key not in self.__dict__:
            self.__dict__[key] = self.smoothed(self.signals[role])
        return self.__dict__[key]

    @property
    def window(self) -> int:
        """Samples in the smoother's window (`smooth`, ~0.1 s)."""
        return max(5, int(round(0.1 / self.dt)) | 1)

    def smoothed(self, x: np.ndarray) -> np.ndarray:
        """Any array over this record's samples through the same smoother (`smooth`, window from `dt`)."""
        window = self.window
        return x if window >= x.size else convolve1d(np.asarray(x, dtype=float), _savgol(window), mode="nearest")

    def noise(self, role: str) -> float:
        """Noise (1 sigma, the signal's unit) left in `smooth(role)`: 0.51 x std(signal - smoothed), the share a
        quadratic Savitzky-Golay smoother of 11 samples keeps of white noise (cached)."""
        key = f"_noise_{role}"
        if key not in self.__dict__:
            self.__dict__[key] = 0.51 * float(np.std(self.signals[role] - self.smooth(role)))
        return self.__dict__[key]

    def rate(self, role: str) -> np.ndarray:
        """Savitzky-Golay rate of signal `role` per second (cached)."""
        key = f"_rate_{role}"
        if key not in self.__dict__:
            self.__dict__[key] = smooth_rate(self.signals[role], self.time)
        return self.__dict__[key]

    def subset(self, rows: np.ndarray) -> "LoopData":
        """The samples `rows` for pointwise models: signals, caches (smoothed signals and rates, computed on
        the whole record first) and the base sliced; sample interval and scales those of the whole record."""
        for role in ("torque", "effort", "motor_velocity", "deflection"):
            if role in self.signals:
                self.smooth(role)
                self.noise(role)
        if "effort" in self.signals:
            self.rate("effort")
        self.scales()
        out = object.__new__(LoopData)
        out.__dict__.update(self.__dict__)
        for key, value in self.__dict__.items():
            if isinstance(value, np.ndarray) and value.shape == (self.n,):
                out.__dict__[key] = value[rows]
        out.signals = {k: v[rows] for k, v in self.signals.items()}
        return out

    @property
    def dt(self) -> float:
        """Median sample interval (s), cached: the step of the fitter's uniform-rate filters."""
        if "_dt" not in self.__dict__:
            self.__dict__["_dt"] = float(np.median(np.diff(self.time)))
        return self.__dict__["_dt"]

    @property
    def n(self) -> int:
        return self.measured.size

    @property
    def time(self) -> np.ndarray:
        return self.signals["time"]

    @property
    def input_torque(self) -> np.ndarray:
        """The torque the compliance direction starts from: the `torque` signal, else the `effort`."""
        return self.signals["torque"] if "torque" in self.signals else self.signals["effort"]

    def unit(self, role: str) -> str:
        return self.units.get(role, SIGNALS[role][0] if role in SIGNALS and self.spring is not None else "1")

    def scales(self) -> Scales:
        """Typical sizes of this data, for the effects' search spaces (cached)."""
        if "_scales" not in self.__dict__:
            self.__dict__["_scales"] = self._scales()
        return self.__dict__["_scales"]

    def _scales(self) -> Scales:
        k = abs(self.gain) or 1.0
        if self.direction == "compliance":
            torque = float(np.max(np.abs(self.input_torque))) or 1.0
            deflection = torque / k
        else:
            d = self.signals.get("deflection")
            deflection = float(np.max(np.abs(d))) if d is not None and np.ptp(d) > 0 else 1.0
            torque = float(np.ptp(self.measured)) or 1.0
        v = self.signals.get("motor_velocity" if "motor_velocity" in self.signals else "velocity")
        velocity = float(np.quantile(np.abs(v), 0.9)) if v is not None else 1.0
        t = self.signals.get("temperature")
        return Scales(deflection_rad=deflection, torque_Nm=torque, velocity_rad_per_s=velocity or 1.0,
                      duration_s=float(np.ptp(self.time)), dt_s=self.dt, k_Nm_per_rad=k,
                      measured_span=float(np.ptp(self.signals["deflection"] if self.sensor_on == "deflection"
                                                 else self.measured)) or 1.0,
                      temperature_C=float(t[0]) if t is not None else 23.0, generic=self.spring is None)


def spring_slope(spring: Effect) -> float:
    """Initial stiffness (Nm/rad) of a linear spring or a torque curve."""
    if hasattr(spring, "curve"):
        return spring.values["scale"] * spring.curve.slope_at_zero()
    return float(spring.values["k_Nm_per_rad"])


def from_frame(df: pd.DataFrame, measured: str, predicted: str, signals: dict[str, str],
               units: dict[str, str] | None = None, measured_unit: str = "1", **options: Any) -> LoopData:
    """A generic LoopData from table columns: `signals` maps role -> column name."""
    for role, column in [("measured", measured), ("predicted", predicted), *signals.items()]:
        if column not in df.columns:
            raise LoopInputError(f"{role} column '{column}' is not in the table; columns: {', '.join(map(str, df.columns))}")
    return LoopData(
        measured=df[measured].to_numpy(float), predicted=df[predicted].to_numpy(float),
        signals={role: df[col].to_numpy(float) for role, col in signals.items()},
        measured_name=measured, measured_unit=measured_unit, units=dict(units or {}),
        columns={"measured": measured, "predicted": predicted, **signals}, **options)


def _window(time: np.ndarray, window_s: float) -> int:
    dt = float(np.median(np.diff(time)))
    return max(5, int(round(window_s / dt)) | 1)


def smooth_rate(x: np.ndarray, time: np.ndarray, window_s: float = 0.1) -> np.ndarray:
    """Rate of x per second by a Savitzky-Golay derivative (quadratic, ~`window_s` s window), so
    sensor noise is not amplified into the velocity the way a plain finite difference does."""
    window = _window(time, window_s)
    dt = float(np.median(np.diff(time)))
    return np.gradient(x, time) if window >= x.size else savgol_filter(x, window, 2, deriv=1, delta=dt)


@lru_cache(maxsize=16)
def _savgol(window: int) -> np.ndarray:
    return savgol_coeffs(window, 2)


def smooth(x: np.ndarray, time: np.ndarray, window_s: float = 0.1) -> np.ndarray:
    """x through a quadratic Savitzky-Golay smoother of ~`window_s` s: one convolution with cached coefficients,
    edges held at the nearest value (scipy's `savgol_filter(..., mode="nearest")`, which a fitter would
    otherwise recompute the coefficients for thousands of times)."""
    window = _window(time, window_s)
    return x if window >= x.size else convolve1d(np.asarray(x, dtype=float), _savgol(window), mode="nearest")


def time_blocks(n: int, n_blocks: int = 10, held_out: tuple[int, ...] = (2, 7)) -> np.ndarray:
    """Boolean mask of held-out samples: `n_blocks` contiguous blocks in time, `held_out` of them held out."""
    block = np.minimum((np.arange(n) * n_blocks) // n, n_blocks - 1)
    return np.isin(block, held_out)
