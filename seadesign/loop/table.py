"""The loop's input: a measured column, a model-prediction column and named signals with roles.

Roles (`ROLES`) say what a signal is, so candidate effects can be built over the signals of
their role (friction over velocity, dead-band and stiffening over displacement, drift over
time, ...). `path` is the part of the prediction that passes through the spring (by default
the whole prediction) and `direction` says how stiffness enters it: `stiffness` (the measured
quantity is a torque computed as k x displacement) or `compliance` (it is a deflection computed
as torque / k). `gain` (measured unit per displacement unit) is the slope of the path term
against the displacement; estimated by least squares when not given.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pandas as pd
from scipy.signal import savgol_filter

from seadesign.errors import DataError

#: role -> meaning (units come from the table; SI unless the column name says otherwise).
ROLES: dict[str, str] = {
    "time": "sample time (s)",
    "displacement": "deflection or position driving the model (rad or m)",
    "velocity": "rate of the displacement (rad/s or m/s)",
    "torque": "a torque or force input (Nm or N)",
    "temperature": "measured temperature (degC)",
    "energy": "cumulative dissipated energy (J)",
    "angle": "link angle for a gravity load (rad)",
}
DIRECTIONS = ("stiffness", "compliance")


class LoopInputError(DataError):
    """The loop's table, columns or roles are unusable (the message names the column and the fix)."""


@dataclass
class LoopData:
    """Arrays of one experiment, time-ordered; units per role in `units` and for the measured column."""

    measured: np.ndarray
    predicted: np.ndarray
    signals: dict[str, np.ndarray]
    measured_name: str = "measured"
    measured_unit: str = "1"
    units: dict[str, str] = field(default_factory=dict)
    columns: dict[str, str] = field(default_factory=dict)
    path: np.ndarray | None = None
    gain: float | None = None
    direction: str = "stiffness"

    def __post_init__(self) -> None:
        self.measured = np.asarray(self.measured, dtype=float)
        self.predicted = np.asarray(self.predicted, dtype=float)
        n = self.measured.size
        if n < 50:
            raise LoopInputError(f"the table has {n} rows; the loop needs at least 50 time-ordered samples")
        if self.predicted.shape != (n,):
            raise LoopInputError("measured and predicted columns differ in length")
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
        for name, values in [(self.measured_name, self.measured), ("predicted", self.predicted), *self.signals.items()]:
            bad = np.flatnonzero(~np.isfinite(values))
            if bad.size:
                raise LoopInputError(f"column '{self.columns.get(name, name)}' is not finite at row {int(bad[0])}; "
                                     "drop or interpolate such rows first")
        if "time" not in self.signals:
            self.signals["time"] = np.arange(n, dtype=float)
            self.units["time"] = "sample"
        if np.any(np.diff(self.signals["time"]) <= 0):
            raise LoopInputError(f"time column '{self.columns.get('time', 'time')}' must strictly increase")
        if "velocity" not in self.signals and "displacement" in self.signals:
            self.signals["velocity"] = smooth_rate(self.signals["displacement"], self.signals["time"])
            self.units["velocity"] = f"{self.units.get('displacement', '1')}/s"
            self.columns["velocity"] = f"d({self.columns.get('displacement', 'displacement')})/dt"
        self.path = self.predicted.copy() if self.path is None else np.asarray(self.path, dtype=float)
        if self.gain is None and "displacement" in self.signals:
            d = self.signals["displacement"]
            self.gain = float(d @ self.path / max(d @ d, 1e-300))

    def smooth(self, role: str) -> np.ndarray:
        """Signal `role` through a quadratic Savitzky-Golay smoother (~0.1 s), cached: the input of
        stateful candidates, so sensor noise does not act as many tiny reversals."""
        key = f"_smooth_{role}"
        if key not in self.__dict__:
            self.__dict__[key] = smooth(self.signals[role], self.time)
        return self.__dict__[key]

    @property
    def dt(self) -> float:
        """Median sample interval (s), cached: the step of the candidates' uniform-rate filters."""
        if "_dt" not in self.__dict__:
            self.__dict__["_dt"] = float(np.median(np.diff(self.time)))
        return self.__dict__["_dt"]

    @property
    def n(self) -> int:
        return self.measured.size

    @property
    def time(self) -> np.ndarray:
        return self.signals["time"]

    def unit(self, role: str) -> str:
        return self.units.get(role, "1")


def from_frame(df: pd.DataFrame, measured: str, predicted: str, signals: dict[str, str],
               units: dict[str, str] | None = None, measured_unit: str = "1", **options) -> LoopData:
    """A LoopData from table columns: `signals` maps role -> column name."""
    for role, column in [("measured", measured), ("predicted", predicted), *signals.items()]:
        if column not in df.columns:
            raise LoopInputError(f"{role} column '{column}' is not in the table; columns: {', '.join(map(str, df.columns))}")
    return LoopData(
        measured=df[measured].to_numpy(float), predicted=df[predicted].to_numpy(float),
        signals={role: df[col].to_numpy(float) for role, col in signals.items()},
        measured_name=measured, measured_unit=measured_unit, units=dict(units or {}),
        columns={"measured": measured, "predicted": predicted, **signals}, **options)


def _window(time: np.ndarray, window_s: float) -> tuple[int, float]:
    dt = float(np.median(np.diff(time)))
    return max(5, int(round(window_s / dt)) | 1), dt


def smooth_rate(x: np.ndarray, time: np.ndarray, window_s: float = 0.1) -> np.ndarray:
    """Rate of x per second by a Savitzky-Golay derivative (quadratic, ~`window_s` s window), so
    sensor noise is not amplified into the velocity the way a plain finite difference does."""
    window, dt = _window(time, window_s)
    return np.gradient(x, time) if window >= x.size else savgol_filter(x, window, 2, deriv=1, delta=dt)


def smooth(x: np.ndarray, time: np.ndarray, window_s: float = 0.1) -> np.ndarray:
    """x through a quadratic Savitzky-Golay smoother of ~`window_s` s."""
    window, _ = _window(time, window_s)
    return x if window >= x.size else savgol_filter(x, window, 2)


def time_blocks(n: int, n_blocks: int = 10, held_out: tuple[int, ...] = (2, 7)) -> np.ndarray:
    """Boolean mask of held-out samples: `n_blocks` contiguous blocks in time, `held_out` of them held out."""
    block = np.minimum((np.arange(n) * n_blocks) // n, n_blocks - 1)
    return np.isin(block, held_out)
