"""Input modalities of the corrector and the thesis's eleven combinations (thesis sec. 6.2.1).

A modality is a group of per-knee channels. Channel names carry their unit. Every corrector
input also starts with the target (the desired Hall/link position, rad), so "target only" is
the empty combination.
"""

from __future__ import annotations

from seadesign.data import FIELD_SIGNALS
from seadesign.errors import SeadesignError

#: signal of the one vocabulary (`seadesign.effects.SIGNALS`) -> the corrector's per-knee channel (unit in the name)
SIGNAL_CHANNELS = {"motor": "motor_pos_rad", "hall": "hall_pos_rad", "motor_velocity": "motor_vel_rad_per_s",
                   "hall_velocity": "hall_vel_rad_per_s", "effort": "effort_Nm"}
#: per-knee field of the robot format (and of the simulator's observation) -> channel
FIELD_CHANNELS = {field: SIGNAL_CHANNELS[signal] for field, signal in FIELD_SIGNALS.items()}

IMU_CHANNELS = (
    "imu_roll_rad", "imu_pitch_rad", "imu_yaw_rad",
    "imu_gyro_x_rad_per_s", "imu_gyro_y_rad_per_s", "imu_gyro_z_rad_per_s",
    "imu_acc_x_m_per_s2", "imu_acc_y_m_per_s2", "imu_acc_z_m_per_s2",
)
PRESSURE_CHANNELS = tuple(f"own_foot_pressure_{i}" for i in range(4)) + tuple(
    f"other_foot_pressure_{i}" for i in range(4)
)

#: modality name -> channels of one knee (the knee's own foot comes first in "pressure").
MODALITIES: dict[str, tuple[str, ...]] = {
    "motor_pos": ("motor_pos_rad",),
    "hall_pos": ("hall_pos_rad",),
    "motor_vel": ("motor_vel_rad_per_s",),
    "hall_vel": ("hall_vel_rad_per_s",),
    "effort": ("effort_Nm",),
    "imu": IMU_CHANNELS,
    "pressure": PRESSURE_CHANNELS,
}

#: the thesis's eleven combinations (table 6.3), each a tuple of modality names.
COMBINATIONS: dict[str, tuple[str, ...]] = {
    "target_only": (),
    "motor_position": ("motor_pos",),
    "hall_motor_position": ("hall_pos", "motor_pos"),
    "velocity": ("motor_vel", "hall_vel"),
    "effort": ("effort",),
    "imu": ("imu",),
    "pressure": ("pressure",),
    "velocity_effort": ("motor_vel", "hall_vel", "effort"),
    "imu_pressure": ("imu", "pressure"),
    "no_hall_position": ("motor_pos", "motor_vel", "hall_vel", "effort", "imu", "pressure"),
    "all": ("motor_pos", "hall_pos", "motor_vel", "hall_vel", "effort", "imu", "pressure"),
}

#: channels that change sign when a right-knee sample is mirrored into the "positive" dataset.
MIRRORED_CHANNELS = frozenset(
    {"target_rad", "motor_pos_rad", "hall_pos_rad", "motor_vel_rad_per_s", "hall_vel_rad_per_s", "effort_Nm"}
)


def resolve_modalities(spec: str | tuple[str, ...] | list[str]) -> tuple[str, ...]:
    """Modality names from a combination name, a comma-separated list, or a sequence of names."""
    if isinstance(spec, str):
        if spec in COMBINATIONS:
            return COMBINATIONS[spec]
        names = tuple(s.strip() for s in spec.split(",") if s.strip())
    else:
        names = tuple(spec)
    unknown = [n for n in names if n not in MODALITIES]
    if unknown:
        raise SeadesignError(
            f"unknown modality {unknown!r} in --modalities; use a combination "
            f"({', '.join(COMBINATIONS)}) or a comma-separated list of {', '.join(MODALITIES)}"
        )
    return names


def channels(modalities: tuple[str, ...]) -> tuple[str, ...]:
    """Per-knee channel names of a modality tuple, in order, without duplicates."""
    out: list[str] = []
    for m in modalities:
        out.extend(c for c in MODALITIES[m] if c not in out)
    return tuple(out)


def unit_of(name: str) -> str:
    """The SI unit encoded in a channel or feature name."""
    if name.startswith("load_share"):
        return "1 (share of the body weight on this leg)"
    for suffix, unit in (("_Nm_per_rad", "Nm/rad"), ("_rad_per_s", "rad/s"), ("_m_per_s2", "m/s^2"), ("_rad", "rad"), ("_Nm", "Nm")):
        if name.endswith(suffix) or f"{suffix}@" in name:
            return unit
    return "1 (pressure cell reading, as recorded)"
