"""Artefact detection in a robot recording, per knee: what a real file contains.

Per file: sample-rate statistics, gaps and an estimate of the dropped samples. Per knee (in
flexion convention, the right knee un-mirrored; deflection = motor - Hall):

- Hall offset: median deflection at rest (motor velocity below `rest_velocity` for at least
  `rest_min_s`), at the first rest (the calibration pose) and over all rest, with the foot
  load at rest (a loaded rest includes the spring's sag under the robot's weight);
- offset per stretch between big jumps (steps, wraps, jumps across gaps), and drift: slope of
  the rest deflection over time within the first such stretch whose rest spans at least 10 s;
- wrap-arounds: Hall jumps within `wrap_tol` of 2 pi not explained by the motor;
- steps: other jumps of the deflection larger than `step_threshold` between samples closer
  than the gap limit (jumps across gaps are counted apart: the robot moved meanwhile);
- glitches: short spikes (Hampel filter, window +-5 samples) of the deflection and effort,
  not counting samples next to a gap;
- stuck segments: the Hall value frozen for at least `stuck_min_s` while the motor moved,
  or entered/left by a jump (a sensor that stopped updating or reports a fixed fallback);
- Hall resolution (smallest step) and the share of samples repeating the previous value.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd

from seadesign.data.robot import KNEE_SIGN, KNEES, PRESSURE_COLUMNS

TWO_PI = 2.0 * np.pi


@dataclass(frozen=True)
class Thresholds:
    """Detection settings (SI units)."""

    gap_factor: float = 3.0  # a gap is a sample interval above gap_factor x the median interval
    rest_velocity: float = 0.05  # rad/s
    rest_min_s: float = 0.5
    step_threshold: float = 0.3  # rad
    wrap_tol: float = 0.5  # rad
    glitch_threshold: float = 0.15  # rad (deflection) ...
    effort_glitch_threshold: float = 2.0  # Nm
    stuck_min_s: float = 0.5
    stuck_motor_range: float = 0.05  # rad


@dataclass
class ArtefactReport:
    """Sampling statistics for the file and a dict of findings per knee ('l', 'r')."""

    source: str
    rows: int
    sampling: dict[str, Any]
    knees: dict[str, dict[str, Any]] = field(default_factory=dict)
    masks: dict[str, dict[str, np.ndarray]] = field(default_factory=dict, repr=False)

    def to_dict(self) -> dict[str, Any]:
        return {"source": self.source, "rows": self.rows, "sampling": self.sampling, "knees": self.knees}

    def format(self) -> str:
        """Human-readable report."""
        s = self.sampling
        lines = [
            f"{self.source}: {self.rows} rows, {s['duration_s']:.2f} s",
            f"  sample rate: median {s['rate_median_hz']:.1f} Hz, mean {s['rate_mean_hz']:.1f} Hz; "
            f"interval p5/p50/p95/max {s['dt_p5_s']*1e3:.1f}/{s['dt_median_s']*1e3:.1f}/{s['dt_p95_s']*1e3:.1f}/"
            f"{s['dt_max_s']*1e3:.1f} ms",
            f"  gaps (> {s['gap_limit_s']*1e3:.1f} ms): {s['gaps']}, {s['gap_time_s']:.2f} s in all, "
            f"about {s['dropped_samples_est']} dropped samples",
        ]
        for side, k in self.knees.items():
            off = k["offset"]
            lines += [
                f"  {side} knee:",
                f"    Hall offset at first rest: {_fmt(off['first_rest_rad'])} rad "
                f"(foot load {_fmt(off['first_rest_pressure'])}); all rest: {_fmt(off['rest_median_rad'])} rad "
                f"over {off['rest_samples']} samples; drift {_fmt(off['drift_rad_per_min'])} rad/min",
                "    offset per stretch between jumps: "
                + ", ".join(f"from {g['start_s']:.2f} s {_fmt(g['offset_rad'])}" for g in off["segments"]),
                f"    wrap-arounds: {len(k['wraps'])}; steps: {len(k['steps'])}"
                + "".join(f" [t={e['time_s']:.2f} s {e['size_rad']:+.3f} rad]" for e in k["steps"][:6])
                + (" ..." if len(k["steps"]) > 6 else ""),
                f"    jumps across gaps: {k['jumps_across_gaps']}; glitches: deflection {k['glitches']}, "
                f"effort {k['effort_glitches']}",
                f"    stuck Hall segments: {len(k['stuck'])}, {k['stuck_time_s']:.2f} s in all"
                + "".join(f" [t={e['start_s']:.2f}-{e['end_s']:.2f} s at {e['value_rad']:.4f} rad]" for e in k["stuck"][:4])
                + (" ..." if len(k["stuck"]) > 4 else ""),
                f"    Hall resolution {_fmt(k['hall_resolution_rad'])} rad; repeated samples {k['repeated_fraction']:.1%}",
            ]
        return "\n".join(lines)


def _fmt(x: float | None) -> str:
    return "n/a" if x is None else f"{x:.4f}"


def sampling_stats(time: np.ndarray, gap_factor: float = 3.0) -> dict[str, Any]:
    """Sample interval statistics, gaps and the estimated number of dropped samples."""
    dt = np.diff(time)
    if dt.size == 0:
        raise ValueError("need at least two samples")
    med = float(np.median(dt))
    gap = dt > gap_factor * med
    return {
        "duration_s": float(time[-1] - time[0]),
        "dt_median_s": med,
        "dt_mean_s": float(dt.mean()),
        "dt_p5_s": float(np.percentile(dt, 5)),
        "dt_p95_s": float(np.percentile(dt, 95)),
        "dt_max_s": float(dt.max()),
        "rate_median_hz": 1.0 / med,
        "rate_mean_hz": float(dt.size / (time[-1] - time[0])),
        "gap_limit_s": gap_factor * med,
        "gaps": int(gap.sum()),
        "gap_time_s": float(dt[gap].sum()),
        "dropped_samples_est": int(np.sum(np.round(dt[gap] / med) - 1)),
        "gap_mask": gap,
    }


def runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """[start, stop) index pairs of the True runs of a boolean array."""
    edges = np.diff(np.concatenate([[0], mask.astype(np.int8), [0]]))
    return list(zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)))


def hampel(x: np.ndarray, half_window: int = 3, threshold: float = 0.1) -> np.ndarray:
    """Samples deviating from their window median by more than max(threshold, 5 x robust sigma)."""
    n = x.size
    if n < 2 * half_window + 1:
        return np.zeros(n, dtype=bool)
    pad = np.pad(x, half_window, mode="edge")
    win = np.lib.stride_tricks.sliding_window_view(pad, 2 * half_window + 1)
    med = np.median(win, axis=1)
    mad = 1.4826 * np.median(np.abs(win - med[:, None]), axis=1)
    return np.abs(x - med) > np.maximum(threshold, 5.0 * mad)


def detect_artefacts(df: pd.DataFrame, thresholds: Thresholds = Thresholds()) -> ArtefactReport:
    """Find the artefacts listed in the module docstring in a table from `read_recording`."""
    th = thresholds
    time = df["time_s"].to_numpy(dtype=float)
    sampling = sampling_stats(time, th.gap_factor)
    gap = sampling.pop("gap_mask")
    pressure = df[PRESSURE_COLUMNS["l"] + PRESSURE_COLUMNS["r"]].to_numpy(dtype=float).sum(axis=1)
    report = ArtefactReport(df.attrs.get("source", "recording"), len(df), sampling)
    for side in KNEES:
        s = KNEE_SIGN[side]
        motor = s * df[f"{side}_knee_pos"].to_numpy(dtype=float)
        hall = s * df[f"{side}_hall_pos"].to_numpy(dtype=float)
        mvel = s * df[f"{side}_knee_vel"].to_numpy(dtype=float)
        effort = s * df[f"{side}_knee_eff"].to_numpy(dtype=float)
        findings, masks = _knee(time, motor, hall, mvel, effort, pressure, gap, th)
        report.knees[side] = findings
        report.masks[side] = masks
    return report


def _knee(time, motor, hall, mvel, effort, pressure, gap, th: Thresholds):
    n = time.size
    deflection = motor - hall
    dhall, dmotor = np.diff(hall), np.diff(motor)
    jump = dhall - dmotor
    big = np.abs(jump) > th.step_threshold
    wrap = big & ~gap & (np.abs(np.abs(dhall) - TWO_PI) < th.wrap_tol)
    step = big & ~gap & ~wrap
    isolated = np.concatenate([[False], gap]) | np.concatenate([gap, [False]])  # a neighbour is far in time
    glitch = hampel(deflection, 5, th.glitch_threshold) & ~isolated
    # a step that a glitch explains is not a level step
    step &= ~(glitch[1:] | glitch[:-1])
    effort_glitch = hampel(effort, 5, th.effort_glitch_threshold) & ~isolated

    stuck_mask = np.zeros(n, dtype=bool)
    stuck = []
    const = np.concatenate([[False], dhall == 0])
    for a, b in runs(const):
        a -= 1  # the run's first sample is the one before the first repeat
        if time[b - 1] - time[a] < th.stuck_min_s:
            continue
        moved = np.ptp(motor[a:b]) > th.stuck_motor_range
        bounded = (a > 0 and big[a - 1]) or (b - 1 < big.size and big[b - 1])
        if moved or bounded:
            stuck_mask[a:b] = True
            stuck.append({"start_s": float(time[a]), "end_s": float(time[b - 1]), "value_rad": float(hall[a]),
                          "rows": [int(a), int(b)]})

    rest = np.zeros(n, dtype=bool)
    slow = (np.abs(mvel) < th.rest_velocity) & ~stuck_mask & ~glitch
    for a, b in runs(slow):
        if time[b - 1] - time[a] >= th.rest_min_s:
            rest[a:b] = True
    rest_runs = runs(rest)
    offset: dict[str, Any] = {"rest_samples": int(rest.sum()), "first_rest_rad": None, "first_rest_pressure": None,
                              "rest_median_rad": None, "drift_rad_per_min": None, "segments": []}
    if rest_runs:
        a, b = rest_runs[0]
        offset["first_rest_rad"] = float(np.median(deflection[a:b]))
        offset["first_rest_pressure"] = float(np.median(pressure[a:b]))
        offset["rest_median_rad"] = float(np.median(deflection[rest]))
    # the offset of each stretch between big jumps (a step, wrap or jump across a gap may change it)
    segment = np.concatenate([[0], np.cumsum(big)])
    for seg in range(int(segment[-1]) + 1):
        sel = rest & (segment == seg)
        start = int(np.flatnonzero(segment == seg)[0])
        offset["segments"].append({"start_s": float(time[start]), "row": start, "rest_samples": int(sel.sum()),
                                   "offset_rad": float(np.median(deflection[sel])) if sel.any() else None})
        if sel.any() and time[sel][-1] - time[sel][0] >= 10.0 and offset["drift_rad_per_min"] is None:
            offset["drift_rad_per_min"] = float(np.polyfit(time[sel], deflection[sel], 1)[0] * 60.0)

    nonzero = np.abs(dhall[dhall != 0])
    findings = {
        "offset": offset,
        "wraps": [{"time_s": float(time[i + 1]), "size_rad": float(dhall[i]), "row": int(i + 1)} for i in np.flatnonzero(wrap)],
        "steps": [{"time_s": float(time[i + 1]), "size_rad": float(jump[i]), "row": int(i + 1)} for i in np.flatnonzero(step)],
        "jumps_across_gaps": int((big & gap).sum()),
        "glitches": int(len(runs(glitch))),
        "effort_glitches": int(len(runs(effort_glitch))),
        "stuck": stuck,
        "stuck_time_s": float(sum(e["end_s"] - e["start_s"] for e in stuck)),
        "hall_resolution_rad": float(np.percentile(nonzero, 1)) if nonzero.size else None,
        "repeated_fraction": float(np.mean(dhall == 0)),
    }
    masks = {"wrap": np.concatenate([[False], wrap]), "step": np.concatenate([[False], step]),
             "jump": np.concatenate([[False], big & gap]), "glitch": glitch,
             "effort_glitch": effort_glitch, "stuck": stuck_mask, "rest": rest}
    return findings, masks
