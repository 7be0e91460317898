"""Cleaning a robot recording as in the thesis (sec. 5.2.3), each step explicit and logged.

Steps, in order (each can be switched off; every removed row is counted by reason):

1. `drop_lifted`: drop rows whose summed foot pressure (all 8 cells, the robot's cell units)
   is below `pressure_threshold` (robot picked up). A recording where every row is below it
   is a hanging recording: refused unless `keep_lifted` says so.
2. `drop_artefacts`: drop rows in stuck Hall segments and rows with deflection or effort
   glitches (see `artefacts.py`).
3. `unwrap`: undo Hall wrap-arounds (add the multiple of 2 pi that the jump removed).
4. `remove_offset`: subtract each knee's Hall offset, estimated as the median deflection at
   unloaded rest (foot pressure below the threshold or `keep_lifted`) in each stretch between
   jumps; rows of a stretch without such rest are dropped (reason `unknown_offset`) rather
   than corrected with a guess; a knee with no unloaded rest at all keeps its offset (logged).
   A loaded rest includes the spring's sag, so it is not used.
5. `euler`: IMU quaternion -> `imu_roll_rad`, `imu_pitch_rad`, `imu_yaw_rad` (ZYX).
6. `normalise`: positions (`*_knee_pos`, `*_hall_pos`, `*_cmd_pos`) divided by pi.
7. `positive`: the right knee's positions, velocities, effort and command sign-flipped so
   both knees look alike (the thesis's "positive" dataset).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from seadesign.data.artefacts import Thresholds, detect_artefacts
from seadesign.data.metadata import write_metadata
from seadesign.data.robot import KNEE_SIGN, KNEES, PRESSURE_COLUMNS, check_recording_frame
from seadesign.errors import DataError


@dataclass
class CleanResult:
    """The cleaned table, the log of steps (dicts) and the removed rows per reason."""

    table: pd.DataFrame
    log: list[dict[str, Any]] = field(default_factory=list)
    removed: dict[str, int] = field(default_factory=dict)

    def format(self) -> str:
        lines = [f"  {s['step']}: {s['detail']}" + (f" (removed {s['removed']} rows)" if s.get("removed") else "")
                 for s in self.log]
        total = sum(self.removed.values())
        return "\n".join(lines + [f"  rows kept: {len(self.table)}, removed: {total} "
                                  + str({k: v for k, v in self.removed.items() if v})])


def is_hanging(df: pd.DataFrame, pressure_threshold: float = 10.0) -> bool:
    """True when every row's foot pressure sum (8 cells) is below the threshold: a hanging recording."""
    pressure = df[PRESSURE_COLUMNS["l"] + PRESSURE_COLUMNS["r"]].to_numpy(dtype=float).sum(axis=1)
    return bool((pressure < pressure_threshold).all())


def clean(df: pd.DataFrame, *, pressure_threshold: float = 10.0, keep_lifted: bool = False,
          drop_artefacts: bool = True, unwrap: bool = True, remove_offset: bool = True,
          euler: bool = True, normalise: bool = True, positive: bool = False,
          thresholds: Thresholds = Thresholds()) -> CleanResult:
    """Clean a table from `read_recording`; see the module docstring for the steps."""
    check_recording_frame(df, df.attrs.get("source", "recording"))
    res = CleanResult(df.reset_index(drop=True).copy())
    res.table.attrs = dict(df.attrs)
    n0 = len(df)
    report = detect_artefacts(res.table, thresholds)
    keep = np.ones(n0, dtype=bool)

    pressure = res.table[PRESSURE_COLUMNS["l"] + PRESSURE_COLUMNS["r"]].to_numpy(dtype=float).sum(axis=1)
    lifted = pressure < pressure_threshold
    if keep_lifted:
        _log(res, "drop_lifted", f"skipped (keep_lifted); {int(lifted.sum())} rows below {pressure_threshold}", 0)
    else:
        if lifted.all():
            raise DataError(
                f"{df.attrs.get('source', 'recording')}: every row has a foot pressure sum below {pressure_threshold} "
                f"(max {pressure.max():.3g}): a hanging recording. Clean it with keep_lifted (--keep-lifted) or a "
                "lower --pressure-threshold"
            )
        _drop(res, keep, lifted, "lifted", "drop_lifted", f"foot pressure sum < {pressure_threshold}")

    if drop_artefacts:
        for side in KNEES:
            m = report.masks[side]
            _drop(res, keep, m["stuck"], f"{side}_hall_stuck", "drop_artefacts", f"{side} knee: stuck Hall segments")
            _drop(res, keep, m["glitch"], f"{side}_hall_glitch", "drop_artefacts", f"{side} knee: deflection glitches")
            _drop(res, keep, m["effort_glitch"], f"{side}_effort_glitch", "drop_artefacts", f"{side} knee: effort glitches")

    table = res.table
    for side in KNEES:
        col = f"{side}_hall_pos"
        if unwrap:
            wraps = report.knees[side]["wraps"]
            hall = table[col].to_numpy(dtype=float).copy()
            for w in wraps:
                hall[w["row"]:] -= 2 * np.pi * np.round(w["size_rad"] / (2 * np.pi))
            table[col] = hall
            _log(res, "unwrap", f"{side} knee: {len(wraps)} wrap-around(s) undone", 0)
        if remove_offset:
            _remove_offset(res, keep, report, side, pressure, pressure_threshold, keep_lifted)

    if euler:
        q = table[["imu_qx", "imu_qy", "imu_qz", "imu_qw"]].to_numpy(dtype=float)
        table["imu_roll_rad"], table["imu_pitch_rad"], table["imu_yaw_rad"] = quaternion_to_euler(q).T
        _log(res, "euler", "IMU quaternion -> imu_roll_rad, imu_pitch_rad, imu_yaw_rad (ZYX)", 0)

    res.table = table.loc[keep].reset_index(drop=True)
    res.table.attrs = dict(df.attrs)
    if normalise:
        for col in [c for c in res.table.columns if c.endswith(("_knee_pos", "_hall_pos", "_cmd_pos"))]:
            res.table[col] = res.table[col] / np.pi
        _log(res, "normalise", "positions (knee, hall, command) divided by pi", 0)
    if positive:
        cols = [c for c in res.table.columns if c.startswith("r_") and "pressure" not in c and "max_current" not in c]
        res.table[cols] = KNEE_SIGN["r"] * res.table[cols]
        _log(res, "positive", f"right knee mirrored: {', '.join(cols)} sign-flipped", 0)
    return res


def _log(res: CleanResult, step: str, detail: str, removed: int) -> None:
    res.log.append({"step": step, "detail": detail, "removed": int(removed)})


def _drop(res: CleanResult, keep: np.ndarray, mask: np.ndarray, reason: str, step: str, detail: str) -> None:
    """Drop rows of `mask` still kept; count them under `reason` (a row counts once, first reason)."""
    new = mask & keep
    keep &= ~mask
    res.removed[reason] = res.removed.get(reason, 0) + int(new.sum())
    _log(res, step, detail, int(new.sum()))


def _remove_offset(res: CleanResult, keep: np.ndarray, report, side: str, pressure: np.ndarray,
                   threshold: float, keep_lifted: bool) -> None:
    t = res.table
    s = KNEE_SIGN[side]
    motor = s * t[f"{side}_knee_pos"].to_numpy(dtype=float)
    hall = s * t[f"{side}_hall_pos"].to_numpy(dtype=float)
    masks = report.masks[side]
    unloaded = np.ones_like(pressure, dtype=bool) if keep_lifted else pressure < threshold
    big = np.flatnonzero(masks["step"] | masks["jump"])  # unwrapped wraps keep the offset
    bounds = [0, *big.tolist(), len(t)]
    offsets, unknown = [], np.zeros(len(t), dtype=bool)
    for a, b in zip(bounds[:-1], bounds[1:]):
        sel = np.zeros(len(t), dtype=bool)
        sel[a:b] = True
        rest = sel & masks["rest"] & unloaded
        if rest.any():
            off = float(np.median(motor[rest] - hall[rest]))
            hall[a:b] += off
            offsets.append(f"{off:+.4f} rad from row {a}")
        else:
            unknown[a:b] = True
    if not offsets:
        _log(res, "remove_offset", f"{side} knee: skipped, no unloaded rest to estimate the offset from (offset kept)", 0)
        return
    t[f"{side}_hall_pos"] = s * hall
    detail = f"{side} knee: Hall offset removed ({'; '.join(offsets) or 'none found'})"
    _drop(res, keep, unknown, f"{side}_unknown_offset", "remove_offset", detail + "; stretches without unloaded rest dropped")


def quaternion_to_euler(q: np.ndarray) -> np.ndarray:
    """(n, 4) quaternions x, y, z, w -> (n, 3) roll, pitch, yaw in rad (ZYX convention)."""
    x, y, z, w = q.T
    roll = np.arctan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y))
    pitch = np.arcsin(np.clip(2 * (w * y - z * x), -1.0, 1.0))
    yaw = np.arctan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))
    return np.stack([roll, pitch, yaw], axis=1)




def write_cleaned(result: CleanResult, path: str | Path, source: str = "") -> Path:
    """Write the cleaned table as a flat CSV (one column per value, names as in the table) and a
    sidecar holding the step log, the removed rows per reason and the column units."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    result.table.to_csv(path, index=False)
    normalised = any(s["step"] == "normalise" for s in result.log)
    pos_unit = "rad/pi" if normalised else "rad"
    units = {c: _unit(c, pos_unit) for c in result.table.columns}
    write_metadata(path, {"format": "seadesign cleaned recording", "source": source, "steps": result.log,
                          "removed_rows": result.removed, "rows": len(result.table), "column_units": units})
    return path


def _unit(column: str, pos_unit: str) -> str:
    if column.endswith(("_knee_pos", "_hall_pos", "_cmd_pos")):
        return pos_unit
    if column.endswith(("_vel", "gyro_x", "gyro_y", "gyro_z")):
        return "rad/s"
    if column.startswith("imu_acc"):
        return "m/s^2"
    if column.endswith("_acc"):
        return "rad/s^2"
    if column.endswith("_eff"):
        return "Nm"
    if column in ("time_s", "timestamp"):
        return "s"
    if column.endswith("_rad"):
        return "rad"
    return "1"
