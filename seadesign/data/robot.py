"""The robot's recording format (thesis, sec. 5.2.3): read, validate and write.

File layout (fixed by the thesis's recorder, so no units in the names): a CSV whose first
column is an unnamed row index, then

    l_knee_pos, l_hall_pos, l_knee_vel, l_hall_vel, l_knee_eff,
    r_knee_pos, r_hall_pos, r_knee_vel, r_hall_vel, r_knee_eff,
    imu, l_pressure, r_pressure, command, timestamp

Positions rad, velocities rad/s, effort Nm, timestamp s. `imu` is a list of 10 values
(quaternion x, y, z, w; gyro x, y, z in rad/s; accel x, y, z in m/s^2), each pressure a list of
4 foot cells, `command` is `[]` or 8 values (pos rad, vel rad/s, acc rad/s^2, max current for
the left knee, then the right). The right knee is mounted mirrored (negative angles).

`read_recording` returns a pandas DataFrame with one typed column per value (see
`RECORDING_COLUMNS`): the scalar columns as in the file, `time_s` (timestamp minus the first
timestamp), the lists expanded into `imu_qx ... imu_acc_z`, `l_pressure_0..3`,
`r_pressure_0..3`, and `has_command` with `l_cmd_pos, l_cmd_vel, l_cmd_acc,
l_cmd_max_current, r_cmd_*` (NaN where the command is `[]`). `df.attrs["source"]` holds the
path and `df.attrs["metadata"]` the sidecar (see `metadata.py`) or None.

Anything malformed (missing column, empty or non-numeric cell, wrong list length,
non-increasing timestamp) raises DataError naming the line, row and column.
`write_recording` writes the same format back (plus an optional sidecar).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from seadesign.data._parse import (
    check_increasing,
    format_lists,
    list_column,
    numeric_column,
    read_raw_csv,
    require_columns,
)
from seadesign.data.metadata import read_metadata, write_metadata
from seadesign.errors import DataError

KNEES = ("l", "r")
KNEE_FIELDS = ("knee_pos", "hall_pos", "knee_vel", "hall_vel", "knee_eff")
SCALAR_COLUMNS = [f"{side}_{field}" for side in KNEES for field in KNEE_FIELDS]
LIST_COLUMNS = ["imu", "l_pressure", "r_pressure", "command"]
FILE_COLUMNS = SCALAR_COLUMNS + LIST_COLUMNS + ["timestamp"]

IMU_COLUMNS = ["imu_qx", "imu_qy", "imu_qz", "imu_qw", "imu_gyro_x", "imu_gyro_y", "imu_gyro_z",
               "imu_acc_x", "imu_acc_y", "imu_acc_z"]
PRESSURE_COLUMNS = {side: [f"{side}_pressure_{i}" for i in range(4)] for side in KNEES}
COMMAND_FIELDS = ("pos", "vel", "acc", "max_current")
COMMAND_COLUMNS = [f"{side}_cmd_{f}" for side in KNEES for f in COMMAND_FIELDS]

#: Columns of the DataFrame `read_recording` returns, in order.
RECORDING_COLUMNS = (
    ["time_s", "timestamp"] + SCALAR_COLUMNS + IMU_COLUMNS + PRESSURE_COLUMNS["l"]
    + PRESSURE_COLUMNS["r"] + ["has_command"] + COMMAND_COLUMNS
)
#: Sign of each knee in the file: the right knee is mirrored.
KNEE_SIGN = {"l": 1.0, "r": -1.0}
#: Knee side in the file -> knee name (the corrector's and the simulator's knee axis: 0 left, 1 right).
KNEE_NAMES = {"l": "left", "r": "right"}
#: Knee name -> its sign in the file (the mirroring that a flexion-convention model undoes).
KNEE_SIGN_BY_NAME = {KNEE_NAMES[side]: KNEE_SIGN[side] for side in KNEES}
#: Per-knee field of the file -> signal of the one vocabulary (`seadesign.effects.SIGNALS`).
FIELD_SIGNALS = {"knee_pos": "motor", "hall_pos": "hall", "knee_vel": "motor_velocity", "hall_vel": "hall_velocity",
                 "knee_eff": "effort"}


@dataclass(frozen=True)
class KneeChannels:
    """One knee's channels as signals of the vocabulary, in flexion convention (the right knee un-mirrored):
    `signals` name -> array (rad, rad/s, Nm), `columns` name -> the column it came from."""

    knee: str
    signals: dict[str, np.ndarray]
    columns: dict[str, str]

    def __getitem__(self, name: str) -> np.ndarray:
        return self.signals[name]


def knee_channels(df: pd.DataFrame, knee: str) -> KneeChannels:
    """The channels of knee `knee` ('l' or 'r', or 'left' / 'right') of a robot-format table."""
    side = {v: k for k, v in KNEE_NAMES.items()}.get(knee, knee)
    if side not in KNEE_SIGN:
        raise DataError(f"knee '{knee}' is unknown; use one of {', '.join(KNEE_SIGN)} (or {', '.join(KNEE_NAMES.values())})")
    columns = {sig: f"{side}_{f}" for f, sig in FIELD_SIGNALS.items()}
    missing = [c for c in columns.values() if c not in df.columns]
    if missing:
        raise DataError(f"the table lacks column(s) {', '.join(missing)}; read it with read_recording")
    s = KNEE_SIGN[side]
    return KneeChannels(side, {sig: s * df[c].to_numpy(dtype=float) for sig, c in columns.items()}, columns)


def read_recording(path: str | Path) -> pd.DataFrame:
    """Read and validate a robot recording; return the typed, expanded table described above."""
    path = Path(path)
    raw = read_raw_csv(path)
    require_columns(raw, FILE_COLUMNS, path, "robot recording")
    out: dict[str, Any] = {}
    timestamp = numeric_column(raw, "timestamp", path)
    check_increasing(timestamp, "timestamp", path)
    out["time_s"] = timestamp - timestamp[0]
    out["timestamp"] = timestamp
    for column in SCALAR_COLUMNS:
        out[column] = numeric_column(raw, column, path)
    imu, _ = list_column(raw, "imu", (10,), path)
    out.update(zip(IMU_COLUMNS, imu.T))
    for side in KNEES:
        cells, _ = list_column(raw, f"{side}_pressure", (4,), path)
        out.update(zip(PRESSURE_COLUMNS[side], cells.T))
    command, counts = list_column(raw, "command", (0, 8), path)
    out["has_command"] = counts == 8
    out.update(zip(COMMAND_COLUMNS, command.T))
    df = pd.DataFrame(out, columns=RECORDING_COLUMNS)
    df.attrs["source"] = str(path)
    df.attrs["metadata"] = read_metadata(path)
    return df


def check_recording_frame(df: pd.DataFrame, source: str = "recording") -> None:
    """DataError unless `df` has every column of RECORDING_COLUMNS with finite numbers where required."""
    missing = [c for c in RECORDING_COLUMNS if c not in df.columns]
    if missing:
        raise DataError(f"{source}: table lacks column(s) {', '.join(missing)}; build it with read_recording or the simulator")
    for column in ["timestamp"] + SCALAR_COLUMNS + IMU_COLUMNS + PRESSURE_COLUMNS["l"] + PRESSURE_COLUMNS["r"]:
        values = df[column].to_numpy(dtype=float)
        bad = np.flatnonzero(~np.isfinite(values))
        if bad.size:
            raise DataError(f"{source}: data row {int(bad[0])}, column '{column}' is not finite ({values[bad[0]]})")
    has = df["has_command"].to_numpy(dtype=bool)
    cmd = df[COMMAND_COLUMNS].to_numpy(dtype=float)
    bad = np.flatnonzero(has & ~np.isfinite(cmd).all(axis=1))
    if bad.size:
        raise DataError(f"{source}: data row {int(bad[0])} has has_command=True but a non-finite command value")
    check_increasing(df["timestamp"].to_numpy(dtype=float), "timestamp", source)


def write_recording(df: pd.DataFrame, path: str | Path, metadata: dict[str, Any] | None = None) -> Path:
    """Write `df` (columns as returned by read_recording) in the robot format; sidecar when `metadata`."""
    path = Path(path)
    check_recording_frame(df, str(path))
    table = pd.DataFrame({c: df[c].to_numpy(dtype=float) for c in SCALAR_COLUMNS})
    table["imu"] = format_lists(df[IMU_COLUMNS].to_numpy(dtype=float))
    for side in KNEES:
        table[f"{side}_pressure"] = format_lists(df[PRESSURE_COLUMNS[side]].to_numpy(dtype=float))
    cmd_text = format_lists(df[COMMAND_COLUMNS].to_numpy(dtype=float))
    has = df["has_command"].to_numpy(dtype=bool)
    table["command"] = [text if flag else "[]" for text, flag in zip(cmd_text, has)]
    table["timestamp"] = df["timestamp"].to_numpy(dtype=float)
    path.parent.mkdir(parents=True, exist_ok=True)
    table.to_csv(path, index=True, float_format=None)
    if metadata is not None:
        write_metadata(path, metadata)
    return path
