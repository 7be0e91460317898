"""Robot recording files -> corrector `Recording`s, through the data module's reader and cleaning.

Each file is read (`seadesign.data.read_recording`) and cleaned (`seadesign.data.clean`: lifted
rows dropped on ground recordings, artefacts dropped, wraps undone, Hall offsets removed, IMU
quaternion -> Euler). A file whose foot pressures are all below the threshold is a hanging
recording and is cleaned with `keep_lifted`. Positions stay in rad and the knees unmirrored
here: the corrector dataset does its own mirroring ("positive") so that it can un-mirror online.

Column mapping (per knee side l / r): `<s>_knee_pos` -> motor_pos_rad, `<s>_hall_pos` ->
hall_pos_rad, `<s>_knee_vel` -> motor_vel_rad_per_s, `<s>_hall_vel` -> hall_vel_rad_per_s,
`<s>_knee_eff` -> effort_Nm, `<s>_cmd_pos` -> command_pos_rad (NaN without a command); the knee's own foot pressure cells first, then the other foot's.
Rows removed by the cleaning and time gaps above `GAP_FACTOR` x the median step split a recording
into segments that no sample pairs across.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from seadesign.corrector.dataset import COMMAND, Recording
from seadesign.corrector.modalities import FIELD_CHANNELS, IMU_CHANNELS, PRESSURE_CHANNELS
from seadesign.data import KNEE_NAMES, clean, is_hanging, read_recording
from seadesign.errors import DataError

GAP_FACTOR = 10.0
PRESSURE_THRESHOLD = 10.0  # summed foot pressure (8 cells, the robot's cell units) below which a row is "lifted"
_IMU_COLUMNS = ["imu_roll_rad", "imu_pitch_rad", "imu_yaw_rad", "imu_gyro_x", "imu_gyro_y", "imu_gyro_z",
                "imu_acc_x", "imu_acc_y", "imu_acc_z"]


def segments(source_row: np.ndarray, time_s: np.ndarray) -> np.ndarray:
    """Segment id per row: a new segment after a removed row or a time gap > GAP_FACTOR x median step."""
    dt = np.diff(time_s)
    med = float(np.median(dt)) if len(dt) else 0.0
    breaks = (np.diff(source_row) != 1) | (dt > GAP_FACTOR * med)
    return np.concatenate([[0], np.cumsum(breaks)])


def recording_from_frame(df: pd.DataFrame, name: str, setting: str = "recorded") -> Recording:
    """Convert a cleaned table (`clean(...).table`, positions in rad, not mirrored) into a Recording.

    Uses column `source_row` (row number in the file) when present to find removed rows.
    """
    if len(df) < 3:
        raise DataError(f"recording {name} has {len(df)} rows after cleaning; at least 3 are needed")
    missing = [c for c in _IMU_COLUMNS if c not in df.columns]
    if missing:
        raise DataError(f"recording {name}: columns {missing} missing; clean it with the Euler step on")
    time_s = df["time_s"].to_numpy(dtype=float)
    imu = df[_IMU_COLUMNS].to_numpy(dtype=float)
    knees = {}
    for s, knee in KNEE_NAMES.items():
        other = "r" if s == "l" else "l"
        ch = {dst: df[f"{s}_{src}"].to_numpy(dtype=float) for src, dst in FIELD_CHANNELS.items()}
        ch[COMMAND] = np.where(df["has_command"].to_numpy(dtype=bool), df[f"{s}_cmd_pos"].to_numpy(dtype=float), np.nan)
        ch.update(zip(IMU_CHANNELS, imu.T))
        cells = np.column_stack([df[[f"{s}_pressure_{i}" for i in range(4)]].to_numpy(float),
                                 df[[f"{other}_pressure_{i}" for i in range(4)]].to_numpy(float)])
        ch.update(zip(PRESSURE_CHANNELS, cells.T))
        knees[knee] = ch
    rows = df["source_row"].to_numpy(dtype=np.int64) if "source_row" in df.columns else np.arange(len(df))
    return Recording(name, time_s, knees, setting, segments(rows, time_s))


def load_recording(path: str | Path) -> tuple[Recording, list[dict]]:
    """Read and clean one recording file; returns the Recording and the cleaning log."""
    return recording_from_table(read_recording(path), Path(path).stem)


def recording_from_table(df: pd.DataFrame, name: str) -> tuple[Recording, list[dict]]:
    """Clean a robot-format table (`read_recording` or the simulator's) and convert it."""
    df = df.copy()
    df["source_row"] = np.arange(len(df))
    hanging = is_hanging(df, PRESSURE_THRESHOLD)
    res = clean(df, pressure_threshold=PRESSURE_THRESHOLD, keep_lifted=hanging, normalise=False, positive=False)
    meta = df.attrs.get("metadata") or {}
    setting = str(meta.get("setting", "hanging" if hanging else "ground"))
    return recording_from_frame(res.table, name, setting), res.log


def load_recordings(paths: list[str | Path]) -> list[Recording]:
    """Read and clean several recording files (order kept)."""
    return [load_recording(p)[0] for p in paths]
