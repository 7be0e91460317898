"""A differentiable PyTorch twin of the knee simulator (`KneeSession`), for training through the closed loop.

`TorchKnee` is built from a `KneeConfig` and an `EffectChain` (or a `KneeSession`'s) and reads every
parameter from them: the servo (P gain, torque limit, no-load speed, stall torque), the link (inertia),
the substep count, and each enabled effect's values and signal bindings. Each effect steps through its one
definition (`Effect.advance`, written against an array namespace) on torch tensors (`array_api_compat`); an
effect that writes or reads a signal the knee does not have at its stage is refused by name. The model is the
one `KneeSession` documents, per knee and in the flexion frame (left-knee sign; `to_robot` mirrors the right
knee):

- servo: u = clamp(Kp (command - qm), +-limit), qm' = clamp(w0 (u - spring torque) / stall, +-w0);
- torque path: deflection qm - angle through the `deflection` effects, the spring (k or the large-deflection
  `TorqueCurve` as its PCHIP polynomial pieces) and the torque effects;
- link: J angle'' = spring torque - load torque, semi-implicit Euler with the session's substeps, each
  substep ending with the torques of its new state; the same static-equilibrium start;
- sensors once per sample: Hall, motor and effort through their effects; hall velocity as the finite
  difference of the Hall reading.

Departures from the NumPy simulator, all for gradients, are the effects' own options (`StepOptions`):

- dead zones (`backlash`, `dead_band`): d -> s softplus((d - b/2) / s) - s softplus((-d - b/2) / s), smoothing
  width s = `dead_zone_smoothing_rad` (default 1e-4 rad; it moves a deflection by at most s ln 2);
- the torque and speed limits stay hard clamps (exact; no gradient through a saturated substep);
- Coulomb friction is the chain's own tanh(v / vs) (already smooth); Dahl hysteresis is exact (its
  kink at a reversal has one-sided derivatives);
- noise (`SensorNoise`) is drawn only with `noise=True`, from seeded torch generators, with the chain's std;
- quantisation rounds like the chain with a straight-through gradient (identity), or is left out with
  `quantise=False`.

A rollout from a saved state (`state()` detached, `load_state`) makes truncated windows for
backpropagation through time:

    knee.reset(target[:, 0], stance[:, 0])
    starts = []
    with torch.no_grad():                         # one pass over the protocol records the window starts
        for _ in range(n_windows):
            starts.append(knee.state())
            rollout(knee, policy, stance, window)
    for start in starts:                          # then each window is trained from its start
        knee.load_state(start)
        out = rollout(knee, policy, stance, window)
        loss(out).backward()
"""

from __future__ import annotations

import math
import zlib
from dataclasses import dataclass, field, fields, replace
from typing import Any, Callable

import array_api_compat.torch as XP
import torch

from seadesign.effects import Effect, EffectChain
from seadesign.effects.base import StepOptions
from seadesign.errors import ConfigError
from seadesign.twin.config import KneeConfig
from seadesign.twin.knee import SIGN, KneeSession
from seadesign.twin.walk import Gait, Trial, knee_targets

Tensor = torch.Tensor
Sig = dict[str, Any]

PHYSICS = ("deflection", "torque", "load_torque")
SENSORS = ("hall", "motor", "effort")
#: signals each stage offers its effects (as in `KneeSession._torques` and `KneeSession._sense`)
AVAILABLE = {"physics": {"time", "angle", "velocity", "stance", *PHYSICS},
             "sensors": {"time", "motor_velocity", *SENSORS}}


def to_robot(x: Tensor) -> Tensor:
    """Flexion frame <-> robot convention (right knee negative) on the last axis (knee: 0 left, 1 right)."""
    return x * torch.as_tensor(SIGN, dtype=x.dtype, device=x.device)


@dataclass
class TorchObservation:
    """What a controller sees at one sample, flexion frame, tensors of the batch shape (..., 2)."""

    hall_rad: Tensor
    motor_rad: Tensor
    motor_velocity_rad_per_s: Tensor
    hall_velocity_rad_per_s: Tensor
    effort_Nm: Tensor


@dataclass
class TorchKneeState:
    """The torch knee between samples: tensors of the batch shape (..., 2), flexion frame. `state()` gives a
    detached copy (a window's start for truncated backpropagation) with the noise streams' states."""

    motor_rad: Tensor
    motor_velocity_rad_per_s: Tensor
    angle_rad: Tensor
    velocity_rad_per_s: Tensor
    spring_torque_Nm: Tensor
    load_torque_Nm: Tensor
    effects: dict[str, dict[str, Any]]  # each stateful effect's state (tensors, tuples of them), by effect name
    previous_hall_rad: Tensor | None  # the last sample's Hall reading (its finite difference is hall velocity)
    sample: int  # samples since reset
    time_s: float
    observation: TorchObservation | None = None
    generators: dict[str, Tensor] = field(default_factory=dict)  # noise streams' states, in a `state()` copy


# -- effects in torch ---------------------------------------------------------------------------------------
@dataclass
class _NormalStream:
    """A noise effect's seeded torch stream, with the one method of NumPy's `Generator` that noise effects draw by."""

    generator: torch.Generator
    dtype: torch.dtype
    device: torch.device

    def standard_normal(self, shape: tuple[int, ...]) -> Tensor:
        return torch.randn(shape, generator=self.generator, dtype=self.dtype, device=self.device)


def _check_stage(effect: Effect) -> None:
    """Refuse `effect` unless it writes a signal of the knee's physics or sensor stage and reads only what the knee
    has there."""
    stage = "physics" if effect.target() in PHYSICS else "sensors" if effect.target() in SENSORS else None
    if stage is None:
        raise ConfigError(f"effect '{effect.name}' ({effect.key}) writes '{effect.target()}', which the torch knee "
                          f"does not model")
    missing = {effect.signal(r) for r in effect.reads} - AVAILABLE[stage]
    if missing:
        raise ConfigError(f"effect '{effect.name}' ({effect.key}) reads {sorted(missing)}, which the knee does not "
                          f"have at its stage; switch it off or use KneeSession")


# -- the knee ------------------------------------------------------------------------------------------------
class TorchKnee:
    """Batched, differentiable knee twin; state tensors of the batch shape (..., 2), knee 0 left, 1 right.

    >>> knee = TorchKnee.from_session(session)            # or TorchKnee(config, chain, rate_hz=100.0)
    >>> obs = knee.reset(flexion_rad, stance)              # static equilibrium at the first target
    >>> for k in range(n): obs = knee.step(policy(obs, k), stance[:, k])

    `rate_hz` sample (command) rate (Hz); `dtype` float64 or float32; `dead_zone_smoothing_rad` the dead zones'
    smoothing width s (rad); `noise` draw the chain's sensor noise; `quantise` round like the chain's encoders
    (straight-through gradient) or pass the value through; `seed` the noise streams' seed.
    """

    def __init__(self, config: KneeConfig, effects: EffectChain, *, rate_hz: float = 100.0,
                 dtype: torch.dtype = torch.float64, device: str | torch.device = "cpu",
                 dead_zone_smoothing_rad: float = 1e-4, noise: bool = False, quantise: bool = True,
                 seed: int = 0) -> None:
        if not (1.0 <= rate_hz <= 10000.0):
            raise ConfigError(f"sample rate {rate_hz} Hz is outside [1, 10000] Hz")
        if not dead_zone_smoothing_rad > 0:
            raise ConfigError(f"dead_zone_smoothing_rad must be > 0 rad, got {dead_zone_smoothing_rad}")
        self.config, self.effects, self.rate_hz = config, effects, float(rate_hz)
        self.dt = 1.0 / self.rate_hz
        self.n_sub = max(1, math.ceil(self.dt / config.max_substep_s - 1e-9))  # as KneeSession
        self.dtype, self.device, self.seed = dtype, torch.device(device), seed
        self.options = StepOptions(float(dead_zone_smoothing_rad), torch.nn.functional.softplus,
                                   Tensor.detach if quantise else None, quantise, noise)
        enabled = effects.enabled()
        for e in enabled:
            _check_stage(e)
        self.stages = {t: [e for e in enabled if e.target() == t] for t in PHYSICS + SENSORS}
        self.values = {e.name: dict(e.values) for e in enabled}  # each effect's values (`vary` puts tensors in)
        self.needs_stance = any("stance" in {e.signal(r) for r in e.reads} for e in enabled)
        self._generators: dict[str, torch.Generator] = {}
        self._state: TorchKneeState | None = None

    @classmethod
    def from_session(cls, session: KneeSession, **options: Any) -> "TorchKnee":
        """The twin of a session: its config, effect chain and sample rate."""
        return cls(session.config, session.effects, rate_hz=session.rate_hz, **options)

    def tensor(self, x: Any) -> Tensor:
        """`x` as a tensor of the knee's dtype and device."""
        return torch.as_tensor(x, dtype=self.dtype, device=self.device)

    def vary(self, effect: str, **values: Any) -> None:
        """Give the enabled effect named `effect` values that differ across the batch (tensors broadcastable to
        the batch shape (..., 2), e.g. a stiffness scale per trial of shape (n_trials, 1)) in place of the chain's
        scalars; only values that enter as factors may vary (e.g. `stiffness_scale`'s scale)."""
        if effect not in self.values:
            raise ConfigError(f"no enabled effect '{effect}' in the torch knee's chain; enable it with "
                              f"EffectChain.configure('{effect}', enabled=True) first")
        batch = self.effects[effect].batch_params
        fixed = sorted(set(values) - set(batch))
        if fixed:
            raise ConfigError(f"effect '{effect}' cannot vary {fixed} across the batch; only "
                              f"{list(batch) or 'none of its values'}")
        self.values[effect].update({name: self.tensor(v) for name, v in values.items()})

    def _noise(self, name: str) -> _NormalStream:
        """The seeded stream of one noise effect (independent of the others, as in `effect_rng`)."""
        if name not in self._generators:
            self._generators[name] = torch.Generator(device=self.device)
            self._generators[name].manual_seed((self.seed * 1_000_003 + zlib.crc32(name.encode())) % 2 ** 63)
        return _NormalStream(self._generators[name], self.dtype, self.device)

    def _run(self, effect: Effect, sig: Sig, state: dict[str, Any], dt: float) -> tuple[Tensor, dict[str, Any]]:
        """One effect's time step (its one definition, `Effect.advance`) on the knee's tensors."""
        return effect.advance(state, sig, dt, self.values[effect.name], self._noise(effect.name) if effect.random
                              else None, XP, self.options)

    # -- physics -------------------------------------------------------------------------------------------
    def _torques(self, qm: Tensor, angle: Tensor, vel: Tensor, stance: Tensor, time_s: float,
                 states: dict[str, dict[str, Tensor]] | None, dt: float) -> tuple[Tensor, Tensor, dict]:
        """Spring and load torque (Nm); states None: stateless effects only, nothing advanced."""
        zero = torch.zeros_like(qm)
        sig: Sig = {"time": torch.full_like(qm, time_s), "angle": angle, "velocity": vel, "stance": stance,
                    "deflection": qm - angle, "torque": zero, "load_torque": zero}
        new = {} if states is None else dict(states)
        for target in PHYSICS:
            for effect in self.stages[target]:
                if effect.stateful and states is None:
                    continue
                sig[target], state = self._run(effect, sig, {} if states is None else states.get(effect.name, {}), dt)
                if effect.stateful:
                    new[effect.name] = state
        return sig["torque"], sig["load_torque"], new

    def _stance(self, stance: Tensor | None, like: Tensor) -> Tensor:
        if stance is None:
            if self.needs_stance:
                raise ConfigError("the chain's ground contact needs each leg's stance share; pass stance")
            return torch.zeros_like(like)
        return self.tensor(stance).expand_as(like)

    def reset(self, flexion_rad: Any, stance: Any = None, seed: int | None = None) -> TorchObservation:
        """Start at the static equilibrium of the link under its loads (as `KneeSession`), motor at
        `flexion_rad` (rad, batch shape (..., 2)), legs carrying `stance`; the noise streams restart from
        `seed` (default: the knee's). Return the first observation."""
        q0 = self.tensor(flexion_rad)
        stance0 = self._stance(stance, q0)
        cfg = self.config
        zero = torch.zeros_like(q0)
        angle = q0
        for _ in range(50):
            torque, load, _ = self._torques(q0, angle, zero, stance0, 0.0, None, 0.0)
            angle = angle + (torque - load) / (cfg.k_Nm_per_rad + 1e-9) * 0.5
        first: Sig = {"time": zero, "angle": angle, "velocity": zero, "stance": stance0, "deflection": q0 - angle,
                      "torque": zero, "load_torque": zero, "hall": angle, "motor": q0, "effort": zero,
                      "motor_velocity": zero}
        states = {e.name: e.init_state(first, None, XP) for stage in self.stages.values() for e in stage if e.stateful}
        torque, load, states = self._torques(q0, angle, zero, stance0, 0.0, states, 0.0)
        self._generators.clear()
        if seed is not None:
            self.seed = int(seed)
        self._state = TorchKneeState(q0, zero, angle, zero, torque, load, states, None, 0, 0.0)
        return self._sense()

    def step(self, command_flex_rad: Tensor, stance: Any = None) -> TorchObservation:
        """Send the motor position command (rad, flexion frame, batch shape) for one sample period (all
        substeps), legs carrying `stance` over it; return the next sample's observation."""
        state = self._require()
        cmd = self.tensor(command_flex_rad)
        if torch.broadcast_shapes(cmd.shape, state.motor_rad.shape) != state.motor_rad.shape:
            raise ConfigError(f"command of shape {tuple(cmd.shape)} does not fit the knees' "
                              f"{tuple(state.motor_rad.shape)}")
        stance_t = self._stance(stance, state.motor_rad)
        cfg = self.config
        h = self.dt / self.n_sub
        limit, stall, w0 = cfg.torque_limit, cfg.stall_torque_Nm, cfg.no_load_speed_rad_per_s
        inv_j = 1.0 / cfg.link_inertia_kg_m2
        qm, vel, angle = state.motor_rad, state.velocity_rad_per_s, state.angle_rad
        torque, load, states, t = state.spring_torque_Nm, state.load_torque_Nm, state.effects, state.time_s
        for _ in range(self.n_sub):
            u = torch.clamp(cfg.p_gain_Nm_per_rad * (cmd - qm), -limit, limit)
            omega = torch.clamp(w0 * (u - torque) / stall, -w0, w0)
            qm = qm + omega * h
            vel = vel + (torque - load) * inv_j * h
            angle = angle + vel * h
            t += h
            torque, load, states = self._torques(qm, angle, vel, stance_t, t, states, h)
        self._state = replace(state, motor_rad=qm, motor_velocity_rad_per_s=omega, velocity_rad_per_s=vel,
                              angle_rad=angle, spring_torque_Nm=torque, load_torque_Nm=load, effects=states,
                              time_s=t, sample=state.sample + 1)
        return self._sense()

    def _sense(self) -> TorchObservation:
        state = self._state
        sig: Sig = {"time": torch.full_like(state.motor_rad, state.sample * self.dt), "hall": state.angle_rad,
                    "motor": state.motor_rad,
                    "effort": state.spring_torque_Nm, "motor_velocity": state.motor_velocity_rad_per_s}
        states = dict(state.effects)
        for target in SENSORS:
            for effect in self.stages[target]:
                sig[target], effect_state = self._run(effect, sig, states.get(effect.name, {}), self.dt)
                if effect.stateful:
                    states[effect.name] = effect_state
        state.effects = states
        hall = sig["hall"]
        previous = state.previous_hall_rad
        hall_vel = torch.zeros_like(hall) if previous is None else (hall - previous) / self.dt
        state.previous_hall_rad = hall
        state.observation = TorchObservation(hall, sig["motor"], state.motor_velocity_rad_per_s, hall_vel,
                                             sig["effort"])
        return state.observation

    def observe(self) -> TorchObservation:
        """The current sample's observation (the one `reset` or the last `step` returned)."""
        return self._require().observation

    @property
    def sample_index(self) -> int:
        """Samples since `reset` (the index of the sample `observe` returns)."""
        return self._require().sample

    # -- windows -------------------------------------------------------------------------------------------
    def _require(self) -> TorchKneeState:
        if self._state is None:
            raise ConfigError("the torch knee has no state; call reset(flexion) or load_state(state) first")
        return self._state

    def state(self) -> TorchKneeState:
        """The current state, detached (a window's start for truncated backpropagation), with the noise streams'
        states."""
        def detach(x: Any) -> Any:
            if isinstance(x, Tensor):
                return x.detach().clone()
            if isinstance(x, dict):
                return {k: detach(v) for k, v in x.items()}
            if isinstance(x, tuple):
                return tuple(detach(v) for v in x)
            if isinstance(x, TorchObservation):
                return TorchObservation(*(detach(getattr(x, f.name)) for f in fields(x)))
            return x
        current = self._require()
        return TorchKneeState(**{f.name: detach(getattr(current, f.name)) for f in fields(current)
                                 if f.name != "generators"},
                              generators={name: g.get_state() for name, g in self._generators.items()})

    def load_state(self, state: TorchKneeState) -> None:
        """Continue from `state` (from `state()`; its tensors may require grad to differentiate w.r.t. it)."""
        self._generators.clear()
        for name, g_state in state.generators.items():
            self._noise(name).generator.set_state(g_state)
        self._state = replace(state, effects={k: dict(v) for k, v in state.effects.items()}, generators={})


# -- protocol and rollout ------------------------------------------------------------------------------------
def protocol_tensors(trials: list[Trial], rate_hz: float = 100.0, gait: Gait = Gait(),
                     dtype: torch.dtype = torch.float64) -> tuple[Tensor, Tensor, Tensor]:
    """`knee_targets` as tensors: time (s, (n_steps,)), flexion targets and stance shares (n_trials, n_steps, 2)."""
    time, target, stance = knee_targets(trials, rate_hz, gait)
    return tuple(torch.as_tensor(a, dtype=dtype) for a in (time, target, stance))


Policy = Callable[[TorchObservation, int], Tensor]


def rollout(knee: TorchKnee, policy: Policy, stance: Tensor | None, n_steps: int) -> dict[str, Tensor]:
    """Run `n_steps` samples from the knee's current state: at sample k (the knee's own index) send
    policy(observation, k) with `stance[:, k]`; return each sample's observation and command stacked on
    axis 1 (batch, n_steps, 2), flexion frame. `stance` is indexed by the absolute sample index."""
    obs = knee.observe()
    names = tuple(f.name for f in fields(TorchObservation))
    log: dict[str, list[Tensor]] = {f: [] for f in names + ("command_rad",)}
    for _ in range(n_steps):
        k = knee.sample_index
        cmd = policy(obs, k)
        for f in names:
            log[f].append(getattr(obs, f))
        log["command_rad"].append(cmd)
        obs = knee.step(cmd, None if stance is None else stance[:, k])
    return {f: torch.stack(v, dim=1) for f, v in log.items()}
