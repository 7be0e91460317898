"""Walk-engine knee trajectories for the thesis's evaluation protocol (sec. 6.1).

A parametric stand-in for the robot's walk engine, shaped after the real recordings
(`free_dtest_part1.csv`: standing at about 1.0 rad, walking around 1.2 rad with swing peaks
near 1.75 rad, about 0.8 s per step cycle): each trial stands, blends into walking, walks
with a fixed direction and speed, and blends back into standing at its end. The left knee swings in the first half of the cycle,
the right one half a cycle later. All angles here are knee flexion (positive, the left knee's
sign); the recording mirrors the right knee.

Directions and speeds follow the thesis: speed in m/s forward, sideways and turning scaled by
0.5 (m/s and rad/s). Speed raises the swing lift and the stance flexion; sideways and turning
make the two legs' lifts differ.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from seadesign.errors import ConfigError

#: direction name -> (forward, sideways (left +), turn (left +)) unit components
DIRECTIONS: dict[str, tuple[float, float, float]] = {
    "front": (1.0, 0.0, 0.0),
    "back": (-1.0, 0.0, 0.0),
    "right": (0.0, -1.0, 0.0),
    "rotate_right": (0.0, 0.0, -1.0),
    "front_right": (1.0, -1.0, 0.0),
    "back_right": (-1.0, -1.0, 0.0),
}
SPEEDS = (0.05, 0.1, 0.2)


@dataclass(frozen=True)
class Trial:
    """One walk: direction (a key of DIRECTIONS), speed (m/s, see module doc), duration_s (s)."""

    direction: str
    speed: float
    duration_s: float = 10.0

    def __post_init__(self) -> None:
        if self.direction not in DIRECTIONS:
            raise ConfigError(f"unknown walk direction '{self.direction}'; use one of {', '.join(DIRECTIONS)}")
        if not (0.0 <= self.speed <= 0.5):
            raise ConfigError(f"walk speed {self.speed} m/s is outside [0, 0.5] m/s")
        if self.duration_s <= 0:
            raise ConfigError(f"trial duration {self.duration_s} s must be positive")


def thesis_protocol(duration_s: float = 10.0, repeats: int = 1) -> list[Trial]:
    """6 directions x 3 speeds (thesis sec. 6.1), `duration_s` each, the whole set `repeats` times."""
    return [Trial(d, s, duration_s) for _ in range(repeats) for d in DIRECTIONS for s in SPEEDS]


@dataclass(frozen=True)
class Gait:
    """Shape of the knee trajectory (rad, s); defaults read off the real recordings."""

    stand_rad: float = 1.0
    walk_base_rad: float = 1.2
    lift_rad: float = 0.55
    stand_s: float = 1.0
    stop_s: float = 0.5  # standing at the end of a trial, so trials join without a jump
    blend_s: float = 0.6
    cycle_s: float = 0.8
    swing_fraction: float = 0.42  # share of the cycle a foot is in the air
    touchdown_fraction: float = 0.04  # share of the cycle over which a foot takes or gives its load
    lift_per_speed: float = 2.0  # relative lift increase per m/s of effective speed
    stance_flex_per_speed: float = 0.8  # rad of stance flexion per m/s of effective speed
    asymmetry_per_speed: float = 1.5  # relative lift difference between legs per m/s sideways/turning


def knee_targets(trials: list[Trial], rate_hz: float, gait: Gait = Gait()) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Sample times (s, from 0), knee targets (rad) and each leg's share of the body weight.

    Returns `time` (n_steps,), `target` (n_trials, n_steps, 2) and `stance` (same shape: 0 in
    swing, 1 in single support, 1/2 each in double support and standing, smooth in between);
    knee axis 0 = left, 1 = right, flexion positive. All trials must have the same duration.
    """
    durations = {t.duration_s for t in trials}
    if len(durations) != 1:
        raise ConfigError(f"trials of one batch must share a duration; got {sorted(durations)} s")
    n_steps = int(round(durations.pop() * rate_hz))
    time = np.arange(n_steps) / rate_hz
    comp = np.array([DIRECTIONS[t.direction] for t in trials]) * np.array([t.speed for t in trials])[:, None]
    comp[:, 1:] *= 0.5  # thesis: sideways and turning scaled by 0.5
    v_eff = np.linalg.norm(comp, axis=1)[:, None, None]
    side = np.array([1.0, -1.0])  # left, right
    lateral = (comp[:, 1] + comp[:, 2])[:, None, None] * side[None, None, :]
    lift = gait.lift_rad * (1.0 + gait.lift_per_speed * v_eff) * (1.0 + gait.asymmetry_per_speed * lateral)

    walk_t = time - gait.stand_s
    phase = (walk_t[None, :, None] / gait.cycle_s + np.array([0.0, 0.5])[None, None, :]) % 1.0
    swinging = phase < gait.swing_fraction
    swing_s = np.where(swinging, phase / gait.swing_fraction, 0.0)
    stance_s = np.where(swinging, 0.0, (phase - gait.swing_fraction) / (1.0 - gait.swing_fraction))
    stop_t = time[-1] + 1.0 / rate_hz - gait.stop_s - time  # time left before the final stand
    walking = (_smoothstep(walk_t / gait.blend_s) * _smoothstep(stop_t / gait.blend_s))[None, :, None]
    gait_shape = (gait.walk_base_rad - gait.stand_rad
                  + lift * np.sin(np.pi * swing_s) ** 2
                  + gait.stance_flex_per_speed * v_eff * np.sin(np.pi * stance_s))
    target = gait.stand_rad + walking * gait_shape
    after_touchdown = (phase - gait.swing_fraction) / gait.touchdown_fraction
    before_liftoff = (1.0 - phase) / gait.touchdown_fraction
    down = np.where(swinging, 0.0, _smoothstep(np.minimum(after_touchdown, before_liftoff)))
    down = 1.0 - walking * (1.0 - down)  # both feet down while standing
    share = down / down.sum(axis=-1, keepdims=True)
    return time, target, np.broadcast_to(share, target.shape).copy()


def _smoothstep(x: np.ndarray) -> np.ndarray:
    x = np.clip(x, 0.0, 1.0)
    return x * x * (3.0 - 2.0 * x)
