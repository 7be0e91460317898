"""Robot recording files -> corrector `Recording`s, through the data module's reader and cleaning.

Column mapping of the data module's table (per knee side l / r): `<s>_knee_pos` -> motor_pos_rad,
`<s>_hall_pos` -> hall_pos_rad, `<s>_knee_vel` -> motor_vel_rad_per_s, `<s>_hall_vel` ->
hall_vel_rad_per_s, `<s>_knee_eff` -> effort_Nm; IMU orientation as roll/pitch/yaw (rad) from the
quaternion; the knee's own foot pressure cells first, then the other foot's. Rows removed by the
cleaning (gaps in the row index) and time gaps longer than `GAP_FACTOR` x the median step split a
recording into segments that no sample pairs across.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from seadesign.corrector.dataset import Recording
from seadesign.corrector.modalities import IMU_CHANNELS, PRESSURE_CHANNELS
from seadesign.data import read_recording
from seadesign.errors import DataError

GAP_FACTOR = 10.0
_SIDES = {"left": "l", "right": "r"}
_KNEE_MAP = {"knee_pos": "motor_pos_rad", "hall_pos": "hall_pos_rad", "knee_vel": "motor_vel_rad_per_s",
             "hall_vel": "hall_vel_rad_per_s", "knee_eff": "effort_Nm"}


def quaternion_to_euler(qx: np.ndarray, qy: np.ndarray, qz: np.ndarray, qw: np.ndarray) -> np.ndarray:
    """(n, 3) roll, pitch, yaw (rad; ZYX convention) from unit quaternions (x, y, z, w)."""
    roll = np.arctan2(2 * (qw * qx + qy * qz), 1 - 2 * (qx * qx + qy * qy))
    pitch = np.arcsin(np.clip(2 * (qw * qy - qz * qx), -1.0, 1.0))
    yaw = np.arctan2(2 * (qw * qz + qx * qy), 1 - 2 * (qy * qy + qz * qz))
    return np.column_stack([roll, pitch, yaw])


def segments(index: np.ndarray, time_s: np.ndarray) -> np.ndarray:
    """Segment id per row: a new segment after a dropped row or a time gap > GAP_FACTOR x median step."""
    dt = np.diff(time_s)
    med = float(np.median(dt)) if len(dt) else 0.0
    breaks = (np.diff(index) != 1) | (dt > GAP_FACTOR * med)
    return np.concatenate([[0], np.cumsum(breaks)])


def recording_from_frame(df: pd.DataFrame, name: str, setting: str = "recorded") -> Recording:
    """Convert a data-module recording table (read_recording / clean output) into a Recording."""
    if len(df) < 3:
        raise DataError(f"recording {name} has {len(df)} rows after cleaning; at least 3 are needed")
    time_s = df["time_s"].to_numpy(dtype=float)
    euler = quaternion_to_euler(*(df[c].to_numpy(dtype=float) for c in ("imu_qx", "imu_qy", "imu_qz", "imu_qw")))
    imu_rest = df[["imu_gyro_x", "imu_gyro_y", "imu_gyro_z", "imu_acc_x", "imu_acc_y", "imu_acc_z"]].to_numpy(float)
    imu = np.column_stack([euler, imu_rest])
    knees = {}
    for knee, s in _SIDES.items():
        other = "r" if s == "l" else "l"
        ch = {dst: df[f"{s}_{src}"].to_numpy(dtype=float) for src, dst in _KNEE_MAP.items()}
        ch.update(zip(IMU_CHANNELS, imu.T))
        cells = np.column_stack([df[[f"{s}_pressure_{i}" for i in range(4)]].to_numpy(float),
                                 df[[f"{other}_pressure_{i}" for i in range(4)]].to_numpy(float)])
        ch.update(zip(PRESSURE_CHANNELS, cells.T))
        knees[knee] = ch
    index = np.asarray(df.index, dtype=np.int64) if pd.api.types.is_integer_dtype(df.index) else np.arange(len(df))
    return Recording(name, time_s, knees, setting, segments(index, time_s))


def load_recordings(paths: list[str | Path]) -> list[Recording]:
    """Read and clean recording files with the data module, then convert them."""
    out = []
    for p in paths:
        df = read_recording(p)
        meta = df.attrs.get("metadata") or {}
        out.append(recording_from_frame(df, Path(p).stem, str(meta.get("setting", "recorded"))))
    return out
