"""Corrector datasets: (inputs at t, command at t+1) samples built from knee recordings.

A `Recording` holds, per knee, the channels of `modalities.MODALITIES` (SI units, robot frame:
the right knee is mounted mirrored and reads negative angles). `build_dataset` turns a list
of recordings into one pooled sample table for a task:

- ``thesis`` (the thesis's dataset code): target = Hall position at t, inputs at t,
  output = motor position at t+1.
- ``inverse`` (better posed for a controller): target = Hall position at t+1 (the position
  the command should produce), inputs at t, output = motor position at t+1.
- ``command`` (the whole actuator's inverse model): target = Hall position at t+1, inputs at t,
  output = the position command sent at t (channel `command_pos_rad`; rows without a recorded
  command are skipped). Unlike the motor position, this includes the servo's own lag.

Knees are pooled. With ``positive=True`` right-knee samples have every signed knee channel and
the output sign-flipped, so both knees look alike (thesis sec. 6.1). ``history`` adds the
modality channels at t-1 ... t-history (in samples) as extra inputs (ANYmal-style window).
Positions stay in rad; the thesis's "/ pi" scaling is a constant factor applied when metrics are
reported in its normalised units.
"""

from __future__ import annotations

from collections import deque
from dataclasses import asdict, dataclass, field

import numpy as np

from seadesign.corrector.modalities import MIRRORED_CHANNELS, MODALITIES, channels, resolve_modalities
from seadesign.data import KNEE_NAMES, KNEE_SIGN_BY_NAME
from seadesign.errors import DataError, SeadesignError

KNEES = tuple(KNEE_NAMES.values())  # ("left", "right")
TASKS = ("thesis", "inverse", "command")
COMMAND = "command_pos_rad"  # optional channel: position command sent at t, rad (NaN where none)
ALL_CHANNELS = channels(tuple(MODALITIES))


@dataclass(frozen=True)
class Recording:
    """One recording: time stamps (s) and, per knee ("left", "right"), every channel (SI units)."""

    name: str
    time_s: np.ndarray
    knees: dict[str, dict[str, np.ndarray]]
    setting: str = "unknown"  # "hanging", "ground" or "sim"
    segment: np.ndarray | None = None  # contiguous-piece id per sample; samples never pair across pieces

    def __post_init__(self) -> None:
        n = len(self.time_s)
        if self.segment is not None and len(self.segment) != n:
            raise DataError(f"recording {self.name}: segment has {len(self.segment)} entries, time_s has {n}")
        for knee in KNEES:
            if knee not in self.knees:
                raise DataError(f"recording {self.name}: knee '{knee}' is missing; give both 'left' and 'right'")
            for ch in ALL_CHANNELS:
                arr = self.knees[knee].get(ch)
                if arr is None:
                    raise DataError(f"recording {self.name}: channel '{ch}' of the {knee} knee is missing")
                if len(arr) != n:
                    raise DataError(
                        f"recording {self.name}: channel '{ch}' of the {knee} knee has {len(arr)} samples, "
                        f"time_s has {n}; cut them to the same length"
                    )


@dataclass(frozen=True)
class DatasetSpec:
    """What a dataset is: the task, modalities, history length (samples) and mirroring."""

    task: str = "thesis"
    modalities: tuple[str, ...] = ("motor_vel", "hall_vel", "effort")
    history: int = 0
    positive: bool = True

    def __post_init__(self) -> None:
        if self.task not in TASKS:
            raise SeadesignError(f"unknown task '{self.task}' (--task); choose one of {', '.join(TASKS)}")
        if self.history < 0:
            raise SeadesignError(f"history must be >= 0 samples, got {self.history} (--history)")
        object.__setattr__(self, "modalities", resolve_modalities(self.modalities))

    def feature_names(self) -> tuple[str, ...]:
        """Input names in order: target, channels at t, then channels at t-1 ... t-history."""
        chans = channels(self.modalities)
        names = ["target_rad", *chans]
        for lag in range(1, self.history + 1):
            names.extend(f"{c}@t-{lag}" for c in chans)
        return tuple(names)

    @classmethod
    def from_dict(cls, d: dict) -> "DatasetSpec":
        """The spec from its `to_dict` form (as stored in a bundle's meta.json)."""
        return cls(d["task"], tuple(d["modalities"]), d["history"], d["positive"])

    def to_dict(self) -> dict:
        """JSON-ready form."""
        d = asdict(self)
        d["modalities"] = list(self.modalities)
        return d


@dataclass
class CorrectorDataset:
    """Pooled samples. X, X_next: (N, d) inputs at t and t+1 (SI); y: (N,) motor position at t+1 (rad).

    Rows in mirrored ("positive") form have sign -1: robot-frame values are sign * value.
    """

    spec: DatasetSpec
    feature_names: tuple[str, ...]
    X: np.ndarray
    X_next: np.ndarray
    y: np.ndarray
    recording: np.ndarray  # index into `recordings`
    knee: np.ndarray  # 0 left, 1 right
    step: np.ndarray  # sample index t within its recording
    time_s: np.ndarray
    sign: np.ndarray
    recordings: tuple[str, ...] = field(default_factory=tuple)

    def __len__(self) -> int:
        return len(self.y)

    def subset(self, idx: np.ndarray) -> "CorrectorDataset":
        """The rows `idx` as a new dataset."""
        return CorrectorDataset(
            self.spec, self.feature_names, self.X[idx], self.X_next[idx], self.y[idx], self.recording[idx],
            self.knee[idx], self.step[idx], self.time_s[idx], self.sign[idx], self.recordings,
        )

    def column(self, name: str) -> np.ndarray:
        """One input column by feature name."""
        return self.X[:, self.feature_names.index(name)]


def _knee_rows(rec: Recording, knee: str, spec: DatasetSpec) -> tuple[np.ndarray, ...]:
    ch = rec.knees[knee]
    n = len(rec.time_s)
    t = np.arange(spec.history, n - 1)
    if rec.segment is not None:  # the window t-history .. t+1 must lie in one contiguous piece
        t = t[rec.segment[t - spec.history] == rec.segment[t + 1]]
    if len(t) == 0:
        raise DataError(
            f"recording {rec.name} has {n} samples, too few for history {spec.history} plus one step ahead"
        )
    chans = channels(spec.modalities)
    hall, motor = ch["hall_pos_rad"], ch["motor_pos_rad"]

    def rows(tt: np.ndarray, target: np.ndarray) -> np.ndarray:
        cols = [target] + [ch[c][tt] for c in chans]
        for lag in range(1, spec.history + 1):
            cols.extend(ch[c][tt - lag] for c in chans)
        return np.column_stack(cols) if cols else np.empty((len(tt), 0))

    target_t = hall[t] if spec.task == "thesis" else hall[t + 1]
    X = rows(t, target_t)
    X_next = rows(t + 1, hall[t + 1])  # the state the command leads to (Siamese pair)
    if spec.task == "command":
        if COMMAND not in ch:
            raise DataError(f"recording {rec.name} has no position commands; task 'command' needs them "
                            "(use --task thesis or inverse)")
        y = ch[COMMAND][t]
    else:
        y = motor[t + 1]
    sign = KNEE_SIGN_BY_NAME[knee] if spec.positive else 1.0
    if sign < 0:
        names = spec.feature_names()
        flip = np.array([-1.0 if n.split("@")[0] in MIRRORED_CHANNELS else 1.0 for n in names])
        X, X_next, y = X * flip, X_next * flip, -y
    return X, X_next, y, t, np.full(len(t), sign)


def build_dataset(recordings: list[Recording], spec: DatasetSpec) -> CorrectorDataset:
    """Pool both knees of every recording into one sample table for `spec`."""
    if not recordings:
        raise DataError("no recordings given (--data); pass at least one recording file")
    parts: list[tuple] = []
    for r, rec in enumerate(recordings):
        for k, knee in enumerate(KNEES):
            X, Xn, y, t, sign = _knee_rows(rec, knee, spec)
            parts.append((X, Xn, y, np.full(len(t), r), np.full(len(t), k), t, rec.time_s[t], sign))
    cols = list(zip(*parts))
    X = np.concatenate(cols[0])
    bad = ~np.isfinite(X).all(axis=1) | ~np.isfinite(np.concatenate(cols[2]))
    if bad.all():
        raise DataError("every sample has a non-finite value; clean the recordings first")
    keep = ~bad
    return CorrectorDataset(
        spec, spec.feature_names(), X[keep], np.concatenate(cols[1])[keep], np.concatenate(cols[2])[keep],
        np.concatenate(cols[3])[keep].astype(int), np.concatenate(cols[4])[keep].astype(int),
        np.concatenate(cols[5])[keep].astype(int), np.concatenate(cols[6])[keep], np.concatenate(cols[7])[keep],
        tuple(r.name for r in recordings),
    )


class FeatureBuilder:
    """Builds one knee's input vector online, step by step, exactly as `build_dataset` lays it out.

    Call `push(channels)` once per control step with the knee's measured channels (robot frame),
    then `inputs(target_rad)` for the current step's input vector (mirrored if the spec is
    positive and the knee is the right one). `unmirror` turns the model output back.
    """

    def __init__(self, spec: DatasetSpec, knee: str) -> None:
        self.spec, self.knee = spec, knee
        self.sign = KNEE_SIGN_BY_NAME[knee] if spec.positive else 1.0
        self._chans = channels(spec.modalities)
        self._past: deque[dict[str, float]] = deque(maxlen=spec.history + 1)
        names = spec.feature_names()
        self._flip = np.array([self.sign if n.split("@")[0] in MIRRORED_CHANNELS else 1.0 for n in names])

    def push(self, values: dict[str, float]) -> None:
        """Record the knee's channels at the current step."""
        self._past.appendleft(values)

    def ready(self) -> bool:
        """True once enough steps are stored for the history window."""
        return len(self._past) == self.spec.history + 1

    def inputs(self, target_rad: float) -> np.ndarray:
        """Input vector at the current step for `target_rad` (robot frame)."""
        if not self._past:
            raise SeadesignError("FeatureBuilder.inputs called before any push()")
        past = list(self._past) + [self._past[-1]] * (self.spec.history + 1 - len(self._past))
        row = [target_rad]
        for lag in range(self.spec.history + 1):
            row.extend(past[lag][c] for c in self._chans)
        return np.asarray(row) * self._flip

    def state(self) -> np.ndarray:
        """The Siamese x_t vector: measured Hall position as 'target' plus the channels at t."""
        return self.inputs(self._past[0]["hall_pos_rad"])

    def unmirror(self, command: float) -> float:
        """Model output (mirrored frame) -> robot-frame motor command, rad."""
        return self.sign * command
