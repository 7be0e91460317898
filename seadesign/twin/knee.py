"""The knee simulator: servo + backlash + SEA spring + lower leg, both knees, robot format out.

Model per knee (SI units, knee flexion positive; the right knee is mirrored only on output):

- servo: P position control on the motor output angle qm with a torque (current) limit:
  u = clip(Kp (command - qm), -limit, limit); a quasi-static DC motor on its torque-speed line
  gives qm' = w0 (u - spring torque) / stall torque, clipped to the no-load speed w0;
- torque path: deflection qm - angle through the `deflection` effects (gearbox `backlash`,
  `dead_band`), the `spring` and the torque effects -> spring torque;
- link: J angle'' = spring torque - load torque (`gravity`, `friction`, `ground_contact`
  in stance), semi-implicit Euler with substeps of at most `max_substep_s`; each substep ends
  with the torques of its new state, so the sampled effort belongs to the sampled angles;
- sensors at each sample: Hall = link angle through the `hall` effects (noise, 12-bit
  quantisation, ...), motor = qm through `motor` effects, effort = spring torque through the
  `effort` effects (gearbox friction, noise); knee_vel = qm', hall_vel = finite difference of
  the Hall reading (as the robot logs it).

Closed loop (`KneeSession`): at each sample the controller gets an `Observation` (the row the
robot would log, plus the walk engine's target) and returns the motor position command to
send, in the robot's convention (right knee negative). `simulate` runs the session with the
walk engine's target relayed unchanged. A batch of trials runs in parallel (vectorised over
trials x knees) and is written one trial after another.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

import numpy as np
import pandas as pd

from seadesign import __version__
from seadesign.constants import G_M_PER_S2
from seadesign.data.robot import COMMAND_COLUMNS, IMU_COLUMNS, KNEE_FIELDS, KNEE_SIGN, PRESSURE_COLUMNS, RECORDING_COLUMNS
from seadesign.effects import EffectChain, effect_rng
from seadesign.errors import ConfigError
from seadesign.design.spring import load_spring
from seadesign.twin.config import KneeConfig, knee_effects
from seadesign.twin.walk import Gait, Trial, knee_targets

SIGN = np.array([KNEE_SIGN["l"], KNEE_SIGN["r"]])  # knee axis: 0 left, 1 right


@dataclass
class Observation:
    """What a controller sees at one sample; arrays (n_trials, 2), knee axis 0 = left, 1 = right.

    Robot convention (right knee negative), as in the recording: `knee_pos` motor encoder (rad),
    `hall_pos` Hall sensor (rad), `knee_vel` (rad/s), `hall_vel` finite difference (rad/s),
    `knee_eff` effort (Nm), `target` the walk engine's command for this sample (rad).
    """

    step: int
    time_s: float
    target: np.ndarray
    knee_pos: np.ndarray
    hall_pos: np.ndarray
    knee_vel: np.ndarray
    hall_vel: np.ndarray
    knee_eff: np.ndarray

    def row(self, trial: int = 0) -> dict[str, float]:
        """One trial's values under the robot format's column names (plus `l_target`, `r_target`)."""
        out = {"time_s": self.time_s}
        for k, side in enumerate("lr"):
            for field in KNEE_FIELDS:
                out[f"{side}_{field}"] = float(getattr(self, field)[trial, k])
            out[f"{side}_target"] = float(self.target[trial, k])
        return out


Controller = Callable[[Observation], np.ndarray]


class KneeSession:
    """Step-wise simulation of a batch of trials at `rate_hz` (the closed-loop API).

    >>> session = KneeSession(spring, thesis_protocol(), ground=True, seed=1)
    >>> obs = session.observe()
    >>> while not session.done:
    ...     obs = session.step(my_controller(obs))   # None -> relay obs.target
    >>> df = session.recording(); meta = session.metadata()
    """

    def __init__(self, spring: dict[str, Any] | str | Path, trials: list[Trial], *, ground: bool = False,
                 rate_hz: float = 100.0, seed: int = 0, effects: EffectChain | None = None,
                 config: KneeConfig | None = None, gait: Gait = Gait(), start_time_s: float = 0.0) -> None:
        if not trials:
            raise ConfigError("no trials to simulate")
        if not (1.0 <= rate_hz <= 10000.0):
            raise ConfigError(f"sample rate {rate_hz} Hz is outside [1, 10000] Hz")
        self.spring = load_spring(spring) if isinstance(spring, (str, Path)) else spring
        self.config = config or KneeConfig.from_spring(self.spring)
        self.effects = effects if effects is not None else knee_effects(self.config, ground)
        self.trials, self.ground, self.rate_hz, self.seed = list(trials), ground, float(rate_hz), int(seed)
        self.gait, self.start_time_s = gait, float(start_time_s)
        self.time, flex_target, self.stance = knee_targets(self.trials, self.rate_hz, gait)
        self.target = flex_target * SIGN  # robot convention
        self.n_trials, self.n_steps = flex_target.shape[:2]
        self.dt = 1.0 / self.rate_hz
        self.n_sub = max(1, math.ceil(self.dt / self.config.max_substep_s - 1e-9))
        self._k = 0
        self._log = {f: np.empty((self.n_trials, self.n_steps, 2)) for f in KNEE_FIELDS + ("command",)}
        self._init_physics(flex_target[:, 0, :])
        self._obs = self._sense()

    # -- public -------------------------------------------------------------------------
    @property
    def done(self) -> bool:
        return self._k >= self.n_steps

    def observe(self) -> Observation:
        """The current sample's observation."""
        if self.done:
            raise ConfigError("the session is finished; read recording()")
        return self._obs

    def step(self, command: np.ndarray | None = None) -> Observation | None:
        """Send `command` (rad, robot convention, shape (n_trials, 2); None = the walk target) for
        one sample period; log the sample; return the next observation (None when done)."""
        obs = self.observe()
        cmd = obs.target if command is None else np.asarray(command, dtype=float)
        if cmd.shape != (self.n_trials, 2) or not np.isfinite(cmd).all():
            raise ConfigError(f"command must be finite with shape ({self.n_trials}, 2) in rad; got {cmd.shape}")
        for field in KNEE_FIELDS:
            self._log[field][:, self._k] = getattr(obs, field)
        self._log["command"][:, self._k] = cmd
        self._advance(cmd * SIGN, self.stance[:, self._k])
        self._k += 1
        if self.done:
            return None
        self._obs = self._sense()
        return self._obs

    def run(self, controller: Controller | None = None) -> pd.DataFrame:
        """Step to the end with `controller` (None: relay the walk target); return the recording."""
        obs = self.observe()
        while obs is not None:
            obs = self.step(None if controller is None else controller(obs))
        return self.recording()

    @property
    def n_logged(self) -> int:
        """Samples logged so far per trial."""
        return self._k

    def recording(self, partial: bool = False) -> pd.DataFrame:
        """The logged samples in the robot format's table (as `read_recording` returns), trials in order.

        A finished session gives every sample. With `partial`, an unfinished one gives the samples
        logged so far (each trial's first `n_logged`, at the times they would have in the full run,
        so trials stay separated by a time gap): the full run's rows up to that sample, except that the
        command's rate and acceleration at the cut are one-sided differences.
        """
        if not self.done and not partial:
            raise ConfigError(f"the session is at sample {self._k} of {self.n_steps}; step to the end first "
                              "or ask for the partial recording")
        m = self._k
        if m < 2:
            raise ConfigError(f"the session has logged {m} sample(s); a recording needs at least 2")
        n = self.n_trials * m
        duration = self.n_steps * self.dt
        stamp = self.start_time_s + (np.arange(self.n_trials)[:, None] * duration + self.time[None, :m])
        out: dict[str, Any] = {"time_s": (stamp - stamp[0, 0]).ravel(), "timestamp": stamp.ravel()}
        for k, side in enumerate("lr"):
            for field in KNEE_FIELDS:
                out[f"{side}_{field}"] = self._log[field][:, :m, k].ravel()
        out.update({c: v.reshape(self.n_trials, self.n_steps)[:, :m].ravel()
                    for c, v in self._imu_and_pressure().items()})
        out["has_command"] = np.ones(n, dtype=bool)
        cmd = self._log["command"][:, :m]
        vel = np.gradient(cmd, self.dt, axis=1)
        acc = np.gradient(vel, self.dt, axis=1)
        for k, side in enumerate("lr"):
            out[f"{side}_cmd_pos"] = cmd[:, :, k].ravel()
            out[f"{side}_cmd_vel"] = vel[:, :, k].ravel()
            out[f"{side}_cmd_acc"] = acc[:, :, k].ravel()
            out[f"{side}_cmd_max_current"] = np.full(n, -1.0)  # the walk engine's "no limit"
        assert set(COMMAND_COLUMNS) <= set(out)
        return pd.DataFrame(out, columns=RECORDING_COLUMNS)

    def metadata(self) -> dict[str, Any]:
        """What was simulated: settings, versions, seed, trials, and every effect (on and off)."""
        duration = self.n_steps * self.dt
        return {
            "format": "seadesign simulated robot recording",
            "simulator": "seadesign.twin.knee",
            "versions": {"seadesign": __version__, "numpy": np.__version__, "pandas": pd.__version__},
            "seed": self.seed,
            "rate_hz": self.rate_hz,
            "substeps": self.n_sub,
            "ground": self.ground,
            "spring": {"study": self.spring.get("study"), "k_Nm_per_rad": self.spring["k_Nm_per_rad"],
                       "k_source": self.spring.get("k_source"), "inputs_hash": self.spring.get("inputs_hash")},
            "config": self.config.as_dict(),
            "gait": self.gait.__dict__,
            "trials": [{"index": i, "direction": t.direction, "speed": t.speed, "duration_s": duration,
                        "start_time_s": i * duration, "rows": [i * self.n_steps, (i + 1) * self.n_steps]}
                       for i, t in enumerate(self.trials)],
            "conventions": "robot format; right knee mirrored (negative); command = motor position sent",
            "effects": self.effects.describe(),
            "effects_enabled": [e.name for e in self.effects.enabled()],
        }

    # -- physics --------------------------------------------------------------------------
    def _init_physics(self, q0: np.ndarray) -> None:
        cfg = self.config
        self.qm = q0.copy()
        self.omega = np.zeros_like(q0)
        self.vel = np.zeros_like(q0)
        self.angle = q0.copy()
        base = {"time": np.zeros_like(q0), "velocity": self.vel, "stance": self.stance[:, 0]}
        for _ in range(50):  # static equilibrium of the link under its loads
            sig = self._torques({**base, "angle": self.angle}, None)
            self.angle = self.angle + (sig["torque"] - sig["load_torque"]) / (cfg.k_Nm_per_rad + 1e-9) * 0.5
        first = {**base, "angle": self.angle, "deflection": self.qm - self.angle, "torque": np.zeros_like(q0),
                 "load_torque": np.zeros_like(q0), "hall": self.angle, "motor": self.qm,
                 "effort": np.zeros_like(q0), "motor_velocity": self.omega}
        self._states = self.effects.start(first, seed=self.seed)
        self._stages = {t: EffectChain.stage(self._states, t)
                        for t in ("deflection", "torque", "load_torque", "hall", "motor", "effort")}
        sig = self._torques({**base, "angle": self.angle}, 0.0)
        self.spring_torque, self.load_torque = sig["torque"], sig["load_torque"]
        self._prev_hall: np.ndarray | None = None
        self._t = 0.0

    def _torques(self, sig: dict[str, np.ndarray], dt: float | None) -> dict[str, np.ndarray]:
        """Spring and load torque for the current state; dt None = evaluate without advancing states."""
        sig["deflection"] = self.qm - sig["angle"]
        sig["torque"] = np.zeros_like(self.qm)
        sig["load_torque"] = np.zeros_like(self.qm)
        for target in ("deflection", "torque", "load_torque"):
            for e, state, rng in (self._stages[target] if dt is not None else
                                  [(e, None, None) for e in self.effects.enabled() if e.target() == target]):
                if dt is None and e.stateful:
                    continue
                sig[target] = e.step(state, sig, dt or 0.0, None, rng) if dt is not None else e.apply(sig)
        return sig

    def _advance(self, command_flex: np.ndarray, stance: np.ndarray) -> None:
        cfg = self.config
        h = self.dt / self.n_sub
        limit, stall, w0 = cfg.torque_limit, cfg.stall_torque_Nm, cfg.no_load_speed_rad_per_s
        inv_j = 1.0 / cfg.link_inertia_kg_m2
        for _ in range(self.n_sub):  # torques of the current state move it; then the new state's torques
            u = np.clip(cfg.p_gain_Nm_per_rad * (command_flex - self.qm), -limit, limit)
            self.omega = np.clip(w0 * (u - self.spring_torque) / stall, -w0, w0)
            self.qm = self.qm + self.omega * h
            self.vel = self.vel + (self.spring_torque - self.load_torque) * inv_j * h
            self.angle = self.angle + self.vel * h
            self._t += h
            sig = self._torques({"time": np.full_like(self.qm, self._t), "angle": self.angle,
                                 "velocity": self.vel, "stance": stance}, h)
            self.spring_torque, self.load_torque = sig["torque"], sig["load_torque"]

    def _sense(self) -> Observation:
        t = self._k * self.dt
        sig = {"time": np.full_like(self.qm, t), "hall": self.angle.copy(), "motor": self.qm.copy(),
               "effort": self.spring_torque.copy(), "motor_velocity": self.omega}
        for target in ("hall", "motor", "effort"):
            for e, state, rng in self._stages[target]:
                sig[target] = e.step(state, sig, self.dt, None, rng)
        hall = sig["hall"] * SIGN
        hall_vel = np.zeros_like(hall) if self._prev_hall is None else (hall - self._prev_hall) / self.dt
        self._prev_hall = hall
        return Observation(self._k, t, self.target[:, self._k], sig["motor"] * SIGN, hall,
                           self.omega * SIGN, hall_vel, sig["effort"] * SIGN)

    # -- auxiliary channels -----------------------------------------------------------------
    def _imu_and_pressure(self) -> dict[str, np.ndarray]:
        """Trunk IMU (gentle gait sway, gravity) and foot cells (weight in stance on the ground)."""
        rng = effect_rng(self.seed, "imu_and_pressure")
        shape = (self.n_trials, self.n_steps)
        walk_t = np.broadcast_to(self.time - self.gait.stand_s, shape)
        sway = np.where(walk_t > 0, np.sin(2 * np.pi * walk_t / self.gait.cycle_s), 0.0)
        roll, pitch = 0.03 * sway, np.full(shape, 0.05)
        cr, sr, cp, sp = np.cos(roll / 2), np.sin(roll / 2), np.cos(pitch / 2), np.sin(pitch / 2)
        quat = np.stack([sr * cp, cr * sp, -sr * sp, cr * cp], axis=-1)
        gyro = np.stack([np.gradient(roll, self.dt, axis=1), np.zeros(shape), np.zeros(shape)], axis=-1)
        acc = G_M_PER_S2 * np.stack([-np.sin(pitch), np.sin(roll) * np.cos(pitch), np.cos(roll) * np.cos(pitch)], axis=-1)
        imu = np.concatenate([quat, gyro + rng.normal(0, 0.01, gyro.shape), acc + rng.normal(0, 0.05, acc.shape)], -1)
        out = {c: imu[..., i].ravel() for i, c in enumerate(IMU_COLUMNS)}
        weight = self.config.stance_weight_share * self.config.mass_kg * G_M_PER_S2 if self.ground else 0.0
        for k, side in enumerate("lr"):
            per_cell = weight * self.stance[:, :, k] / 4.0
            cells = per_cell[..., None] * (1.0 + rng.normal(0, 0.1, shape + (4,)))
            cells = np.abs(cells + rng.normal(0, 0.05, shape + (4,)))
            out.update({c: cells[..., i].ravel() for i, c in enumerate(PRESSURE_COLUMNS[side])})
        return out


def simulate(spring: dict[str, Any] | str | Path, trials: list[Trial], **options: Any) -> tuple[pd.DataFrame, dict[str, Any]]:
    """Run `KneeSession(spring, trials, **options)` with the walk target relayed; return (table, metadata)."""
    session = KneeSession(spring, trials, **options)
    return session.run(), session.metadata()
