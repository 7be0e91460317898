"""Synthetic knee recordings with a known answer, for tests and benchmarks without real data.

The motor follows a walking-like trajectory; a load torque tau deflects an ideal linear spring,
so hall = motor - tau / k exactly, and the recorded effort equals tau (plus optional noise).
The right knee is the mirror image (negative angles), as on the robot.
"""

from __future__ import annotations

import numpy as np

from seadesign.data import KNEE_SIGN_BY_NAME

from seadesign.corrector.dataset import KNEES, Recording
from seadesign.corrector.modalities import IMU_CHANNELS, PRESSURE_CHANNELS


def linear_spring_recording(k_Nm_per_rad: float, duration_s: float = 30.0, rate_Hz: float = 100.0,
                            stride_Hz: float = 1.2, effort_noise_Nm: float = 0.0, seed: int = 0,
                            name: str = "synthetic") -> Recording:
    """A recording of both knees walking with an ideal spring of stiffness k (Nm/rad)."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, duration_s, 1.0 / rate_Hz)
    knees = {}
    for side, knee in enumerate(KNEES):
        phase = np.pi * side + rng.uniform(0, 2 * np.pi)
        w = 2 * np.pi * stride_Hz
        motor = 1.2 + 0.25 * np.sin(w * t + phase) + 0.08 * np.sin(2 * w * t + 0.5 * phase)
        tau = 1.0 + 2.0 * np.sin(w * t + phase + 0.7) + 0.4 * np.sin(3 * w * t)
        hall = motor - tau / k_Nm_per_rad
        effort = tau + effort_noise_Nm * rng.standard_normal(len(t))
        sign = KNEE_SIGN_BY_NAME[knee]
        ch = {
            "motor_pos_rad": sign * motor, "hall_pos_rad": sign * hall, "effort_Nm": sign * effort,
            "motor_vel_rad_per_s": sign * np.gradient(motor, t), "hall_vel_rad_per_s": sign * np.gradient(hall, t),
            "command_pos_rad": sign * np.append(motor[1:], motor[-1]),  # an ideal servo reaches it next sample
        }
        for i, c in enumerate(IMU_CHANNELS):
            ch[c] = 0.05 * np.sin(w * t + i) + 0.01 * rng.standard_normal(len(t))
        for i, c in enumerate(PRESSURE_CHANNELS):
            ch[c] = np.clip(2.0 * np.sin(w * t + phase + i), 0, None)
        knees[knee] = ch
    return Recording(name, t, knees, setting="sim")
