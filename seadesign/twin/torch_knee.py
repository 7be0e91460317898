"""A differentiable PyTorch twin of the knee simulator (`KneeSession`), for training through the closed loop.

`TorchKnee` is built from a `KneeConfig` and an `EffectChain` (or a `KneeSession`'s) and reads every
parameter from them: the servo (P gain, torque limit, no-load speed, stall torque), the link (inertia),
the substep count, and each enabled effect's values and signal bindings. An enabled effect without a
torch form here is refused by name. The model is the one `KneeSession` documents, per knee and in the
flexion frame (left-knee sign; `to_robot` mirrors the right knee):

- servo: u = clamp(Kp (command - qm), +-limit), qm' = clamp(w0 (u - spring torque) / stall, +-w0);
- torque path: deflection qm - angle through the `deflection` effects, the spring (k or the large-deflection
  `TorqueCurve` as its PCHIP polynomial pieces) and the torque effects;
- link: J angle'' = spring torque - load torque, semi-implicit Euler with the session's substeps, each
  substep ending with the torques of its new state; the same static-equilibrium start;
- sensors once per sample: Hall, motor and effort through their effects; hall velocity as the finite
  difference of the Hall reading.

Departures from the NumPy simulator, all for gradients:

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

import numpy as np
import torch
from scipy.interpolate import PchipInterpolator

from seadesign.effects import Effect, EffectChain
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
    effects: dict[str, dict[str, Tensor]]  # each stateful effect's state, by effect name
    previous_hall_rad: Tensor | None  # the last sample's Hall reading (its finite difference is hall velocity)
    sample: int  # samples since reset
    time_s: float
    observation: TorchObservation | None = None
    generators: dict[str, Tensor] = field(default_factory=dict)  # noise streams' states, in a `state()` copy


# -- effects in torch ---------------------------------------------------------------------------------------
class _Op:
    """One enabled effect of the chain in torch: its values and bindings are the effect's own. `per_knee`: the
    values that may differ across the batch (`TorchKnee.vary`): those that enter only as torch factors."""

    stateful = False
    per_knee: tuple[str, ...] = ()

    def __init__(self, effect: Effect, options: "_Options") -> None:
        self.effect, self.name, self.target = effect, effect.name, effect.target()
        self.p = dict(effect.values)
        self.options = options

    def reads(self) -> set[str]:
        return {self.effect.signal(r) for r in self.effect.reads} | {self.target}

    def x(self, sig: Sig, role: str) -> Tensor:
        return sig[self.effect.signal(role)]

    def init(self, sig: Sig) -> dict[str, Tensor]:
        return {}

    def __call__(self, sig: Sig, state: dict[str, Tensor], dt: float) -> tuple[Tensor, dict[str, Tensor]]:
        raise NotImplementedError


class _DeadZone(_Op):
    def __call__(self, sig, state, dt):
        d, h, s = self.x(sig, "deflection"), 0.5 * self.p["width_rad"], self.options.dead_zone_smoothing_rad
        f = torch.nn.functional.softplus
        return s * (f((d - h) / s) - f((-d - h) / s)), state


class _LinearSpring(_Op):
    def __call__(self, sig, state, dt):
        return self.x(sig, "torque") + self.p["k_Nm_per_rad"] * self.x(sig, "deflection"), state


class _CurveSpring(_Op):
    """The `TorqueCurve`'s PCHIP interpolant (the same one it builds from its points) as polynomial pieces."""

    def __init__(self, effect, options):
        super().__init__(effect, options)
        self.curve = effect.curve
        pchip = PchipInterpolator(self.curve.rotation_rad, self.curve.torque_Nm, extrapolate=False)
        self.breaks = torch.as_tensor(pchip.x, dtype=options.dtype, device=options.device)
        self.coef = torch.as_tensor(pchip.c, dtype=options.dtype, device=options.device)  # (4, pieces)

    def torque(self, d: Tensor) -> Tensor:
        a = d.abs()
        end = self.curve.end_rotation_rad
        if not self.curve.hard_stop and bool((a > end).any()):
            self.curve.torque(np.array([float(a.max())]))  # raises the curve's own CurveRangeError
        a = a.clamp(max=end)
        i = (torch.searchsorted(self.breaks, a.detach(), right=True) - 1).clamp(0, self.coef.shape[1] - 1)
        c, u = self.coef[:, i], a - self.breaks[i]
        return torch.sign(d) * (((c[0] * u + c[1]) * u + c[2]) * u + c[3])

    def __call__(self, sig, state, dt):
        return self.x(sig, "torque") + self.p["scale"] * self.torque(self.x(sig, "deflection")), state


class _Scale(_Op):
    per_knee = ("scale",)

    def __call__(self, sig, state, dt):
        return self.p["scale"] * self.x(sig, "torque"), state


class _Cubic(_Op):
    def __call__(self, sig, state, dt):
        return self.x(sig, "torque") + self.p["k3_Nm_per_rad3"] * self.x(sig, "deflection") ** 3, state


class _Dahl(_Op):
    stateful = True

    def init(self, sig):
        d = self.x(sig, "deflection")
        return {"z": torch.zeros_like(d), "d": d}

    def __call__(self, sig, state, dt):
        d, th = self.x(sig, "deflection"), self.p["torque_Nm"]
        step = d - state["d"]
        s = torch.sign(step)
        z = s * th + (state["z"] - s * th) * torch.exp(-self.p["stiffness_Nm_per_rad"] * step.abs() / th)
        return self.x(sig, "torque") + z, {"z": z, "d": d}


class _Viscoelastic(_Op):
    stateful = True

    def init(self, sig):
        return {"relaxed": self.x(sig, "deflection")}

    def __call__(self, sig, state, dt):
        d = self.x(sig, "deflection")
        relaxed = state["relaxed"] + (d - state["relaxed"]) * (1.0 - math.exp(-dt / self.p["relaxation_time_s"]))
        return self.x(sig, "torque") + self.p["maxwell_stiffness_Nm_per_rad"] * (d - relaxed), {"relaxed": relaxed}


class _Thermal(_Op):
    stateful = True

    def init(self, sig):
        d = self.x(sig, "deflection")
        return {"heat": torch.zeros_like(d), "d": d}

    def __call__(self, sig, state, dt):
        d, tau, c = self.x(sig, "deflection"), self.x(sig, "torque"), self.p["softening_per_J"]
        kept = state["heat"] * math.exp(-dt / self.p["cooling_time_s"])
        work = (tau * (d - state["d"])).abs()
        f = ((1.0 - c * kept) / (1.0 + c * work)).clamp(min=0.05)
        return tau * f, {"heat": kept + f * work, "d": d}


class _Friction(_Op):
    def __call__(self, sig, state, dt):
        v = self.x(sig, "velocity")
        coulomb = self.p["coulomb_Nm"] * torch.tanh(v / self.p["smoothing_rad_per_s"])
        return self.x(sig, "load_torque") + coulomb + self.p["viscous_Nm_s_per_rad"] * v, state


class _Gravity(_Op):
    def __call__(self, sig, state, dt):
        angle = self.x(sig, "angle")
        return self.x(sig, "load_torque") + self.p["amplitude_Nm"] * torch.sin(angle + self.p["angle_offset_rad"]), state


class _Stance(_Op):
    def __call__(self, sig, state, dt):
        q = self.x(sig, "angle")
        l1, l2 = self.p["upper_leg_m"], self.p["lower_leg_m"]
        lean = torch.atan2(l1 * torch.sin(q), l2 + l1 * torch.cos(q))
        return self.x(sig, "load_torque") - self.x(sig, "stance") * self.p["weight_N"] * l2 * torch.sin(lean), state


class _Offset(_Op):
    def __call__(self, sig, state, dt):
        return self.x(sig, "hall") + self.p["offset_rad"], state


class _Timed(_Op):
    """Sensor effects of the time since the first sample (drift, step)."""

    stateful = True

    def init(self, sig):
        return {"t0": torch.as_tensor(sig["time"], dtype=self.options.dtype, device=self.options.device)}


class _Drift(_Timed):
    def __call__(self, sig, state, dt):
        return self.x(sig, "hall") + self.p["rate_rad_per_s"] * (sig["time"] - state["t0"]), state


class _Step(_Timed):
    def __call__(self, sig, state, dt):
        jumped = (sig["time"] - state["t0"] >= self.p["time_s"]).to(self.options.dtype)
        return self.x(sig, "hall") + self.p["size_rad"] * jumped, state


class _Delay(_Op):
    """reading(t) = value(t - td) interpolated linearly between samples, held at the first sample before it:
    `SensorDelay` at the fixed sample interval, on a buffer of the last floor(td / dt) + 2 samples."""

    stateful = True

    def __call__(self, sig, state, dt):
        v = self.x(sig, "hall")
        lag = self.p["delay_s"] / dt
        whole = math.floor(lag)
        frac = lag - whole
        buffer = state.get("buffer")
        if buffer is None:  # the first sample fills the past
            buffer = v.unsqueeze(0).expand(whole + 2, *v.shape)
        buffer = torch.cat([buffer[1:], v.unsqueeze(0)])
        return buffer[-1 - whole] * (1.0 - frac) + buffer[-2 - whole] * frac, {"buffer": buffer}


class _Noise(_Op):
    def __call__(self, sig, state, dt):
        v = self.x(sig, "hall")
        if not self.options.noise:
            return v, state
        gen = self.options.generator(self.name)
        draw = torch.randn(v.shape, generator=gen, dtype=v.dtype, device=v.device)
        return v + self.p["std_rad"] * draw, state


class _Quantise(_Op):
    def __call__(self, sig, state, dt):
        v = self.x(sig, "hall")
        if not self.options.quantise:
            return v, state
        q = 2.0 * math.pi / 2.0 ** self.p["bits"]
        return v + (torch.round(v / q) * q - v).detach(), state  # straight-through: gradient of the identity


class _Wrap(_Op):
    def __call__(self, sig, state, dt):
        c = self.p["centre_rad"]
        return torch.remainder(self.x(sig, "hall") - c + math.pi, 2.0 * math.pi) - math.pi + c, state


class _EffortLag(_Op):
    stateful = True

    def init(self, sig):
        return {"y": self.x(sig, "effort")}

    def __call__(self, sig, state, dt):
        y = state["y"] + (self.x(sig, "effort") - state["y"]) * (1.0 - math.exp(-dt / self.p["time_constant_s"]))
        return y, {"y": y}


#: effect key -> torch form; the stages each may act in
_OPS: dict[str, tuple[type[_Op], tuple[str, ...]]] = {
    "dead_band": (_DeadZone, ("physics",)),
    "spring": (_LinearSpring, ("physics",)),
    "spring_curve": (_CurveSpring, ("physics",)),
    "stiffness_scale": (_Scale, ("physics",)),
    "cubic_stiffening": (_Cubic, ("physics",)),
    "hysteresis": (_Dahl, ("physics",)),
    "viscoelastic": (_Viscoelastic, ("physics",)),
    "thermal_softening": (_Thermal, ("physics",)),
    "friction": (_Friction, ("physics", "sensors")),
    "gravity": (_Gravity, ("physics",)),
    "ground_contact": (_Stance, ("physics",)),
    "sensor_offset": (_Offset, ("physics", "sensors")),
    "sensor_drift": (_Drift, ("sensors",)),
    "sensor_step": (_Step, ("sensors",)),
    "sensor_delay": (_Delay, ("sensors",)),
    "sensor_noise": (_Noise, ("physics", "sensors")),
    "quantisation": (_Quantise, ("physics", "sensors")),
    "angle_wrap": (_Wrap, ("physics", "sensors")),
    "effort_lag": (_EffortLag, ("sensors",)),
}


@dataclass
class _Options:
    dtype: torch.dtype
    device: torch.device
    dead_zone_smoothing_rad: float
    noise: bool
    quantise: bool
    seed: int

    def __post_init__(self) -> None:
        self.generators: dict[str, torch.Generator] = {}

    def generator(self, name: str) -> torch.Generator:
        """The seeded stream of one noise effect (independent of the others, as in `effect_rng`)."""
        if name not in self.generators:
            gen = torch.Generator(device=self.device)
            gen.manual_seed((self.seed * 1_000_003 + zlib.crc32(name.encode())) % 2 ** 63)
            self.generators[name] = gen
        return self.generators[name]


def _build_op(effect: Effect, options: _Options) -> _Op:
    if effect.key not in _OPS:
        raise ConfigError(f"effect '{effect.name}' ({effect.key}) has no differentiable form in the torch knee; "
                          f"switch it off or use KneeSession; supported: {', '.join(sorted(_OPS))}")
    cls, stages = _OPS[effect.key]
    stage = "physics" if effect.target() in PHYSICS else "sensors" if effect.target() in SENSORS else None
    if stage not in stages:
        raise ConfigError(f"effect '{effect.name}' ({effect.key}) writes '{effect.target()}', which the torch knee "
                          f"does not model for this effect")
    op = cls(effect, options)
    missing = op.reads() - AVAILABLE[stage]
    if missing:
        raise ConfigError(f"effect '{effect.name}' reads {sorted(missing)}, which the knee does not have at its stage")
    return op


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
        self.options = _Options(dtype, torch.device(device), float(dead_zone_smoothing_rad), noise, quantise, seed)
        ops = [_build_op(e, self.options) for e in effects.enabled()]
        self.stages = {t: [op for op in ops if op.target == t] for t in PHYSICS + SENSORS}
        self.needs_stance = any("stance" in op.reads() for op in ops)
        self._state: TorchKneeState | None = None

    @classmethod
    def from_session(cls, session: KneeSession, **options: Any) -> "TorchKnee":
        """The twin of a session: its config, effect chain and sample rate."""
        return cls(session.config, session.effects, rate_hz=session.rate_hz, **options)

    def tensor(self, x: Any) -> Tensor:
        """`x` as a tensor of the knee's dtype and device."""
        return torch.as_tensor(x, dtype=self.options.dtype, device=self.options.device)

    def vary(self, effect: str, **values: Any) -> None:
        """Give the enabled effect named `effect` values that differ across the batch (tensors broadcastable to
        the batch shape (..., 2), e.g. a stiffness scale per trial of shape (n_trials, 1)) in place of the chain's
        scalars; only values that enter as factors may vary (e.g. `stiffness_scale`'s scale)."""
        ops = {op.name: op for ops in self.stages.values() for op in ops}
        if effect not in ops:
            raise ConfigError(f"no enabled effect '{effect}' in the torch knee's chain; enable it with "
                              f"EffectChain.configure('{effect}', enabled=True) first")
        op = ops[effect]
        fixed = sorted(set(values) - set(op.per_knee))
        if fixed:
            raise ConfigError(f"effect '{effect}' cannot vary {fixed} across the batch; only "
                              f"{list(op.per_knee) or 'none of its values'}")
        op.p.update({name: self.tensor(v) for name, v in values.items()})

    # -- physics -------------------------------------------------------------------------------------------
    def _torques(self, qm: Tensor, angle: Tensor, vel: Tensor, stance: Tensor, time_s: float,
                 states: dict[str, dict[str, Tensor]] | None, dt: float) -> tuple[Tensor, Tensor, dict]:
        """Spring and load torque (Nm); states None: stateless effects only, nothing advanced."""
        zero = torch.zeros_like(qm)
        sig: Sig = {"time": time_s, "angle": angle, "velocity": vel, "stance": stance,
                    "deflection": qm - angle, "torque": zero, "load_torque": zero}
        new = {} if states is None else dict(states)
        for target in PHYSICS:
            for op in self.stages[target]:
                if op.stateful and states is None:
                    continue
                sig[target], state = op(sig, {} if states is None else states.get(op.name, {}), dt)
                if op.stateful:
                    new[op.name] = state
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
        first: Sig = {"time": 0.0, "angle": angle, "velocity": zero, "stance": stance0, "deflection": q0 - angle,
                      "torque": zero, "load_torque": zero, "hall": angle, "motor": q0, "effort": zero,
                      "motor_velocity": zero}
        states = {op.name: op.init(first) for ops in self.stages.values() for op in ops if op.stateful}
        torque, load, states = self._torques(q0, angle, zero, stance0, 0.0, states, 0.0)
        self.options.generators.clear()
        if seed is not None:
            self.options.seed = int(seed)
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
        sig: Sig = {"time": state.sample * self.dt, "hall": state.angle_rad, "motor": state.motor_rad,
                    "effort": state.spring_torque_Nm, "motor_velocity": state.motor_velocity_rad_per_s}
        states = dict(state.effects)
        for target in SENSORS:
            for op in self.stages[target]:
                sig[target], effect_state = op(sig, states.get(op.name, {}), self.dt)
                if op.stateful:
                    states[op.name] = effect_state
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
            if isinstance(x, TorchObservation):
                return TorchObservation(*(detach(getattr(x, f.name)) for f in fields(x)))
            return x
        current = self._require()
        return TorchKneeState(**{f.name: detach(getattr(current, f.name)) for f in fields(current)
                                 if f.name != "generators"},
                              generators={name: g.get_state() for name, g in self.options.generators.items()})

    def load_state(self, state: TorchKneeState) -> None:
        """Continue from `state` (from `state()`; its tensors may require grad to differentiate w.r.t. it)."""
        self.options.generators.clear()
        for name, g_state in state.generators.items():
            self.options.generator(name).set_state(g_state)
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
