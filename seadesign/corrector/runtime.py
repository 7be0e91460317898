"""Correctors as run in a control loop: one call per knee and step, target in, motor command out.

All correctors share `command(knee, target_rad, measured, dt_s) -> command_rad`, where
`measured` holds the knee's channels at this step (names of `modalities.MODALITIES`, robot
frame, SI). `reset()` clears internal state between trials.

- `NoCorrection`: command = target.
- `HallPI`: the thesis's PI on the Hall error e = target - hall (kp 0.2, ki 0.1 by default).
- `FeedForward`: command = target + effort / k (adds the deflection a linear spring of
  stiffness k shows under the measured torque). The effort is low-pass filtered (time constant
  `filter_s`): fed back unfiltered it also carries the link's inertial torque, and the loop
  through the servo then acts as an undamped integral controller on the Hall error that
  oscillates (seen in the knee simulator). At rest the filter changes nothing.
- `NetCorrector`: a trained network (NumPy path of an exported bundle).
- `ReferenceFeedForward`: a network on the reference window only (`reference.py`), plus an optional
  low-gain PI on the Hall error; it reads the walk engine's preview (`preview_steps` > 0), which the
  closed loop passes as `preview=`.
- `ClosedLoopCorrector`: a policy trained through the closed loop (`closedloop_training`): the same
  reference window plus a feedback on the Hall error and its rate, its gain bounded by construction.
"""

from __future__ import annotations

from typing import Protocol

import numpy as np

from seadesign.corrector.dataset import KNEES, DatasetSpec, FeatureBuilder
from seadesign.corrector.export import NumpyClosedLoop, NumpyCorrector
from seadesign.corrector.reference import Preview, ReferenceBuffer, ReferenceWindow, knee_window
from seadesign.data import KNEE_SIGN_BY_NAME
from seadesign.design.spring import TorqueCurve
from seadesign.errors import SeadesignError

#: single-call latency budget of a corrector (us): it has to fit a 1 kHz robot loop (measured in benchmarks/)
STEP_BUDGET_US = 50.0


class Corrector(Protocol):
    """What the open- and closed-loop evaluations drive."""

    name: str

    def reset(self) -> None: ...

    def command(self, knee: str, target_rad: float, measured: dict[str, float], dt_s: float) -> float: ...


class NoCorrection:
    """Send the target unchanged."""

    def __init__(self, name: str = "none") -> None:
        self.name = name

    def reset(self) -> None:
        """Nothing to reset."""

    def command(self, knee: str, target_rad: float, measured: dict[str, float], dt_s: float) -> float:
        return target_rad


class HallPI:
    """PI on the Hall error: command = target + kp e + ki integral(e dt), e = target - hall (rad)."""

    def __init__(self, kp: float = 0.2, ki: float = 0.1, name: str = "pi") -> None:
        self.kp, self.ki, self.name = kp, ki, name
        self._integral = {k: 0.0 for k in KNEES}

    def reset(self) -> None:
        self._integral = {k: 0.0 for k in KNEES}

    def command(self, knee: str, target_rad: float, measured: dict[str, float], dt_s: float) -> float:
        e = target_rad - measured["hall_pos_rad"]
        self._integral[knee] += e * dt_s
        return target_rad + self.kp * e + self.ki * self._integral[knee]


class FeedForward:
    """Physics feed-forward: command = target + the spring's deflection under the lowpassed effort: effort / k
    (k in Nm/rad from spring.json), or the large-deflection curve's rotation at that torque when spring.json
    carries one (never extrapolated: an effort past its end is a CurveRangeError, or its end stop).
    `filter_s`: filter time constant in s (0 = unfiltered)."""

    def __init__(self, k_Nm_per_rad: float, curve: TorqueCurve | None = None, filter_s: float = 0.1,
                 name: str = "feedforward") -> None:
        if k_Nm_per_rad <= 0:
            raise SeadesignError(f"k_Nm_per_rad must be > 0, got {k_Nm_per_rad}")
        if filter_s < 0:
            raise SeadesignError(f"feed-forward filter time constant must be >= 0 s, got {filter_s}")
        self.k, self.curve, self.filter_s, self.name = k_Nm_per_rad, curve, filter_s, name
        self.reset()

    def reset(self) -> None:
        self._effort: dict[str, float | None] = {k: None for k in KNEES}

    def command(self, knee: str, target_rad: float, measured: dict[str, float], dt_s: float) -> float:
        tau, prev = measured["effort_Nm"], self._effort[knee]
        if prev is not None and self.filter_s > 0:
            tau = prev + (tau - prev) * min(1.0, dt_s / self.filter_s)
        self._effort[knee] = tau
        return target_rad + (tau / self.k if self.curve is None else float(self.curve.rotation(tau)))


class NetCorrector:
    """A trained network driven online; builds its inputs exactly as the training dataset did."""

    def __init__(self, model: NumpyCorrector, spec: DatasetSpec, name: str) -> None:
        self.model, self.spec, self.name = model, spec, name
        self.reset()

    def reset(self) -> None:
        self._builders = {k: FeatureBuilder(self.spec, k) for k in KNEES}

    def command(self, knee: str, target_rad: float, measured: dict[str, float], dt_s: float) -> float:
        b = self._builders[knee]
        b.push(measured)
        x = b.inputs(target_rad)
        if self.model.siamese:  # x_t: measured state; x_t+1: the target with this step's channels (thesis 6.2.3)
            x = np.concatenate([b.state(), x])
        return b.unmirror(float(self.model(x)))


class ReferenceFeedForward:
    """command = target + network(reference window) + kp e + ki integral(e dt), e = target - hall (flexion).

    The network (NumPy path) maps `reference.reference_features` to the command (rad, flexion); the
    right knee is mirrored in and out. `kp`, `ki` (1, 1/s): the outer PI, 0 to switch it off.
    """

    def __init__(self, model: NumpyCorrector, window: ReferenceWindow, k_Nm_per_rad: float, kp: float = 0.0,
                 ki: float = 0.0, name: str = "reference") -> None:
        self.model, self.window, self.k, self.kp, self.ki, self.name = model, window, k_Nm_per_rad, kp, ki, name
        self.preview_steps = window.preview
        self.reset()

    def reset(self) -> None:
        self._buffers = {k: ReferenceBuffer(self.window, self.k) for k in KNEES}
        self._integral = {k: 0.0 for k in KNEES}

    def command(self, knee: str, target_rad: float, measured: dict[str, float], dt_s: float,
                preview: Preview | None = None) -> float:
        sign = KNEE_SIGN_BY_NAME[knee]
        target, x = knee_window(self._buffers[knee], sign, target_rad, preview, self.name)
        e = target - sign * measured["hall_pos_rad"]
        self._integral[knee] += e * dt_s
        return sign * (float(self.model(x)) + self.kp * e + self.ki * self._integral[knee])


class ClosedLoopCorrector:
    """command = ff(x) + L [h(m, x) - h(0, x)] (`export.NumpyClosedLoop`; flexion, the right knee mirrored in and
    out): x the reference window kept here from the walk engine's preview (as `ReferenceFeedForward`), m the Hall
    error e = target - hall and its rate (the target's finite difference minus the measured Hall velocity) times
    the policy's `rate_time_s`, both rad."""

    def __init__(self, model: NumpyClosedLoop, window: ReferenceWindow, k_Nm_per_rad: float,
                 name: str = "closedloop") -> None:
        self.model, self.window, self.k, self.name = model, window, float(k_Nm_per_rad), name
        self.preview_steps = window.preview
        self._m = np.empty(2)
        self.reset()

    def reset(self) -> None:
        self._buffers = {k: ReferenceBuffer(self.window, self.k) for k in KNEES}
        self._prev_target: dict[str, float | None] = {k: None for k in KNEES}

    def command(self, knee: str, target_rad: float, measured: dict[str, float], dt_s: float,
                preview: Preview | None = None) -> float:
        sign = KNEE_SIGN_BY_NAME[knee]
        target, x = knee_window(self._buffers[knee], sign, target_rad, preview, self.name)
        prev = self._prev_target[knee]
        self._prev_target[knee] = target
        rate = (0.0 if prev is None else (target - prev) / dt_s) - sign * measured["hall_vel_rad_per_s"]
        self._m[0], self._m[1] = target - sign * measured["hall_pos_rad"], self.model.rate_time_s * rate
        return sign * float(self.model.command(x, self._m))
