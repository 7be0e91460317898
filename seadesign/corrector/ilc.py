"""Iterative learning control in the knee simulator: the command that makes the knee follow a trajectory.

The "expert" labels of the feed-forward corrector. For a batch of trials the simulator is run
again and again with a command sequence u_j (knee flexion, rad) and the Hall error
e_j = target - Hall is fed back into the next trial (inverse-model ILC with a Q filter):

    u_j+1 = target + clip(Q[u_j + gain * P^-1 e_j] - target, +-max_correction_rad)

P^-1 is the linearised inverse of the knee (servo P loop with the motor's torque-speed line,
the spring k, the link's inertia and viscous friction): for a wanted change e of the link
angle, the spring deflection changes by (J e'' + b e') / k, the motor by that plus e, and
the command by the motor's change plus (motor rate / a + spring torque) / Kp, with
a = no-load speed / stall torque. Q is a zero-phase Butterworth low pass (`filter_hz`), which
keeps the non-causal update smooth and the iteration convergent above the knee's resonance.
The bound on the correction keeps the command inside what the servo can use (a load the
spring cannot follow, e.g. the foot taking the body weight, would otherwise wind it up).

Noise effects are switched off in the runs (the labels are the deterministic expert answer);
quantisation and every other effect of the chain stay. The iteration stops on a plateau: the
mean |error| improved by less than `min_improvement` (relative) over `patience` iterations;
the result is the best iterate. A batch that reaches `max_iterations` before its plateau is
reported as not converged, and its commands are not used as labels.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.signal import butter, filtfilt

from seadesign.effects import EffectChain
from seadesign.errors import SeadesignError
from seadesign.twin import KneeSession, Trial
from seadesign.twin.config import KneeConfig, knee_effects
from seadesign.twin.knee import SIGN
from seadesign.twin.walk import Gait

#: effects drawing random numbers, off while learning the expert commands
NOISE_EFFECTS = ("hall_noise", "effort_noise")


@dataclass(frozen=True)
class ILCSettings:
    """gain (1), Q-filter cut-off (Hz), bound on |command - target| (rad), stopping rule."""

    gain: float = 0.7
    filter_hz: float = 8.0
    max_correction_rad: float = 1.0
    max_iterations: int = 40
    min_improvement: float = 0.01
    patience: int = 3

    def __post_init__(self) -> None:
        if not 0.0 < self.gain <= 1.5:
            raise SeadesignError(f"ILC gain must be in (0, 1.5], got {self.gain}")
        if self.filter_hz <= 0 or self.max_correction_rad <= 0 or self.max_iterations < 1 or self.patience < 1:
            raise SeadesignError("ILC filter_hz and max_correction_rad must be > 0, max_iterations and patience >= 1")


@dataclass(frozen=True)
class LinearKnee:
    """The knee linearised for the learning operator (SI): spring k, link inertia J, viscous friction b,
    servo P gain Kp and motor speed per torque a = no-load speed / stall torque."""

    k_Nm_per_rad: float
    inertia_kg_m2: float
    viscous_Nm_s_per_rad: float
    p_gain_Nm_per_rad: float
    speed_per_torque_rad_per_s_Nm: float

    @classmethod
    def of(cls, config: KneeConfig, effects: EffectChain) -> "LinearKnee":
        friction = effects["friction"]
        return cls(config.k_Nm_per_rad, config.link_inertia_kg_m2,
                   friction.values["viscous_Nm_s_per_rad"] if friction.enabled else 0.0,
                   config.p_gain_Nm_per_rad, config.no_load_speed_rad_per_s / config.stall_torque_Nm)


def inverse_command(e_rad: np.ndarray, dt_s: float, knee: LinearKnee) -> np.ndarray:
    """Command change (rad) that moves the link by `e_rad` (time on axis 1) through the linearised knee."""
    d = lambda x: np.gradient(x, dt_s, axis=1)  # noqa: E731
    torque = knee.inertia_kg_m2 * d(d(e_rad)) + knee.viscous_Nm_s_per_rad * d(e_rad)
    motor = e_rad + torque / knee.k_Nm_per_rad
    return motor + (d(motor) / knee.speed_per_torque_rad_per_s_Nm + torque) / knee.p_gain_Nm_per_rad


@dataclass
class ILCResult:
    """Learned commands of a batch of trials; arrays (n_trials, n_steps, 2) in knee flexion (rad), knee
    axis 0 left, 1 right. `load_share`: the leg's share of the body weight where it stands on the ground
    (0 everywhere when hanging). `mean_abs_error_rad`: the Hall error of each iteration (iteration 0:
    no correction)."""

    trials: list[Trial]
    ground: bool
    rate_hz: float
    gait: Gait
    k_Nm_per_rad: float
    target_rad: np.ndarray
    load_share: np.ndarray
    command_rad: np.ndarray
    mean_abs_error_rad: list[float] = field(default_factory=list)
    best_iteration: int = 0
    converged: bool = False

    @property
    def correction_rad(self) -> np.ndarray:
        return self.command_rad - self.target_rad


def _run(session: KneeSession, command_flex: np.ndarray) -> np.ndarray:
    """Hall reading (flexion, rad) of a session driven by `command_flex`."""
    hall = np.empty_like(command_flex)
    obs, t = session.observe(), 0
    while obs is not None:
        hall[:, t] = obs.hall_pos * SIGN
        obs = session.step(command_flex[:, t] * SIGN)
        t += 1
    return hall


def learn_commands(spring: dict, trials: list[Trial], *, ground: bool = False, rate_hz: float = 100.0,
                   gait: Gait = Gait(), config: KneeConfig | None = None, effects: EffectChain | None = None,
                   settings: ILCSettings = ILCSettings()) -> ILCResult:
    """Run ILC on `trials` in the knee simulator (`config` / `effects` as KneeSession takes them)."""
    config = config or KneeConfig.from_spring(spring)
    chain = effects if effects is not None else knee_effects(config, ground)
    for name in NOISE_EFFECTS:
        if name in chain.names():
            chain = chain.configure(name, enabled=False)

    def session() -> KneeSession:
        return KneeSession(spring, trials, ground=ground, rate_hz=rate_hz, config=config, effects=chain, gait=gait)

    first = session()
    target = first.target * SIGN
    load = first.stance * float(ground)
    knee = LinearKnee.of(config, chain)
    b, a = butter(4, settings.filter_hz / (0.5 * rate_hz))
    u, best_u, errors, best = target.copy(), target.copy(), [], 0
    for j in range(settings.max_iterations):
        e = target - _run(first if j == 0 else session(), u)
        errors.append(float(np.mean(np.abs(e))))
        if errors[-1] < errors[best] or j == 0:
            best, best_u = j, u
        if j >= settings.patience and errors[j - settings.patience] - min(errors[-settings.patience:]) \
                < settings.min_improvement * errors[j - settings.patience]:
            return ILCResult(list(trials), ground, rate_hz, gait, config.k_Nm_per_rad, target, load, best_u,
                             errors, best, True)
        step = u + settings.gain * inverse_command(filtfilt(b, a, e, axis=1), 1.0 / rate_hz, knee)
        u = target + np.clip(filtfilt(b, a, step, axis=1) - target, -settings.max_correction_rad,
                             settings.max_correction_rad)
    return ILCResult(list(trials), ground, rate_hz, gait, config.k_Nm_per_rad, target, load, best_u, errors, best, False)
