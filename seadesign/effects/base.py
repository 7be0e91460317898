"""The effect abstraction: one physical effect, its parameters, and one forward model used two ways.

An `Effect` reads named signals and returns a new value for one signal (`writes`). Signals
are numpy arrays with time on the last axis (any leading batch axes). Signal names and units
are listed in `SIGNALS`; an instance may bind its roles to other signal names (`bind`), so the
same dead-band can act on a bench deflection or a robot deflection, and friction can act on
the link or on the motor side.

Two uses of the same object:

- fitting / post-processing: `apply(signals, params)` maps whole recorded arrays at once;
- time stepping (the simulators): `init_state(sample, params)` then `step(state, sample, dt,
  params, rng)` once per time step on arrays of the batch shape.

Both give the same result (tested for every effect). The time step is written once, against an array
namespace `xp` (NumPy, or torch through `array_api_compat`): `advance` is the step as a function, which the
NumPy simulators (`step`) and the differentiable torch knee (`twin.torch_knee`) both call; `StepOptions`
holds the torch knee's smooth departures (softplus dead zones, straight-through quantisation).

Parameters are `Param` records with a unit, a default and physical bounds; `params` arguments are mappings name ->
value that override the instance's values, so a fitter can pass trial values without copying objects. Additive
effects add to the current value of their target (zero when the signal is absent).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Callable, ClassVar, Mapping

import numpy as np
from scipy.signal import lfilter

from seadesign.errors import ConfigError

Signals = Mapping[str, np.ndarray]
Array = Any  # an array of the step's namespace: a NumPy array or a torch tensor

#: Signal vocabulary: name -> (unit, meaning). Rotations: knee flexion positive.
SIGNALS: dict[str, tuple[str, str]] = {
    "time": ("s", "sample time"),
    "deflection": ("rad", "deflection of the torque path: motor output minus link angle"),
    "torque": ("Nm", "torque the spring transmits to the link"),
    "angle": ("rad", "link (knee) angle"),
    "velocity": ("rad/s", "link angular velocity"),
    "load_torque": ("Nm", "torque the link needs from the spring beyond inertia (gravity, contact, friction)"),
    "stance": ("1", "share of the supported body weight this leg carries (0 in swing)"),
    "hall": ("rad", "Hall sensor reading of the link angle"),
    "motor": ("rad", "motor encoder reading"),
    "motor_velocity": ("rad/s", "motor output angular velocity"),
    "hall_velocity": ("rad/s", "finite difference of the Hall reading (as the robot logs it)"),
    "effort": ("Nm", "torque the servo reports (from its current)"),
    "deflection_rate": ("rad/s", "rate of the deflection (bench: the spring's twist rate)"),
    "torque_sensor": ("Nm", "a bench's torque-sensor reading of the spring torque"),
    "temperature": ("degC", "measured spring temperature (optional)"),
    "energy": ("J", "cumulative dissipated energy (optional)"),
}


@dataclass(frozen=True)
class Param:
    """A parameter: name, unit, default, physical bounds [lower, upper], meaning."""

    name: str
    unit: str
    default: float
    lower: float
    upper: float
    doc: str


@dataclass(frozen=True)
class Scales:
    """Typical sizes of the data an effect is fitted to: what its data-dependent bounds and starts scale with.

    `deflection_rad` largest |deflection|, `torque_Nm` largest |spring torque|, `velocity_rad_per_s`
    90 % quantile of the |velocity| that drives friction, `duration_s` record length, `dt_s` median
    sample interval, `k_Nm_per_rad` slope of the spring, `measured_span` span of the reading the sensor
    effects act on (the measured channel, or a bench's deflection reading; in its unit). Names carry the SEA units; on a generic table they stand for the table's units.
    """

    deflection_rad: float = 1.0
    torque_Nm: float = 1.0
    velocity_rad_per_s: float = 1.0
    duration_s: float = 1.0
    dt_s: float = 0.01
    k_Nm_per_rad: float = 1.0
    measured_span: float = 1.0
    temperature_C: float = 23.0  # at the first sample, when the data has a temperature
    generic: bool = False  # a table of unknown sign conventions: loads and delays may take either sign


@dataclass(frozen=True)
class StepOptions:
    """How a time step departs from the exact model, for a simulator that differentiates through it (the torch
    knee); the default (`EXACT`) is the exact model.

    `dead_zone_smoothing_rad`: None, exact dead zones; s (rad), d -> s softplus((d - b/2) / s) - s softplus((-d - b/2)
    / s) (it moves a deflection by at most s ln 2); `softplus`: the namespace's softplus (torch's, for its gradient);
    `stop_gradient`: None, encoders round; a function that detaches an array from its graph, they round with the
    gradient of the identity (straight-through); `quantise`: False, encoders pass the value through; `noise`:
    False, noise effects add nothing."""

    dead_zone_smoothing_rad: float | None = None
    softplus: Callable[[Array], Array] | None = None
    stop_gradient: Callable[[Array], Array] | None = None
    quantise: bool = True
    noise: bool = True


EXACT = StepOptions()


#: A fit's search space for one effect: bounds name -> (lower, upper) (equal bounds: held fixed) and start points.
Search = tuple[dict[str, tuple[float, float]], list[dict[str, float]]]


class Effect:
    """Base class; subclasses set the class attributes and implement `_map` or the stateful trio."""

    key: ClassVar[str]
    summary: ClassVar[str]
    signature: ClassVar[str] = ""  # what the effect leaves in a residual when a model lacks it
    parameters: ClassVar[tuple[Param, ...]] = ()
    reads: ClassVar[tuple[str, ...]] = ()
    writes: ClassVar[str]
    stateful: ClassVar[bool] = False
    random: ClassVar[bool] = False
    log_params: ClassVar[tuple[str, ...]] = ()  # positive scale parameters a fitter searches in log space
    batch_params: ClassVar[tuple[str, ...]] = ()  # values that may differ across a batch (they enter as factors)

    def __init__(self, name: str | None = None, *, enabled: bool = True,
                 bind: Mapping[str, str] | None = None, **values: float) -> None:
        self.name = name or self.key
        self.enabled = enabled
        self.bind = dict(bind or {})
        unknown_roles = set(self.bind) - set(self.reads) - {self.writes}
        if unknown_roles:
            raise ConfigError(f"effect '{self.name}': cannot bind {sorted(unknown_roles)}; roles are {self.roles()}")
        self.values = {p.name: float(p.default) for p in self.parameters}
        self.values.update(self._check(values))
        self._bound = tuple((role, self.signal(role)) for role in self.roles())  # (role, signal name), once

    # -- parameters -------------------------------------------------------------------
    def _check(self, values: Mapping[str, float]) -> dict[str, float]:
        known = {p.name: p for p in self.parameters}
        out = {}
        for name, value in values.items():
            if name not in known:
                raise ConfigError(
                    f"effect '{self.name}' has no parameter '{name}'; parameters: {', '.join(known) or 'none'}"
                )
            p = known[name]
            value = float(value)
            if not (p.lower <= value <= p.upper):
                raise ConfigError(
                    f"effect '{self.name}': {name} = {value} {p.unit} is outside its physical bounds "
                    f"[{p.lower}, {p.upper}] {p.unit}"
                )
            out[name] = value
        return out

    def resolve(self, params: Mapping[str, float] | None = None) -> dict[str, float]:
        """Instance values overridden by `params` (checked against names and bounds)."""
        return {**self.values, **self._check(params or {})}

    def replace(self, *, enabled: bool | None = None, **values: float) -> "Effect":
        """A copy with some values (and/or the on/off switch) changed."""
        return type(self)(self.name, enabled=self.enabled if enabled is None else enabled,
                          bind=self.bind, **{**self.values, **values})

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Lower and upper bounds in the order of `parameters`."""
        return (np.array([p.lower for p in self.parameters]), np.array([p.upper for p in self.parameters]))

    def search(self, scales: Scales) -> Search:
        """Bounds and start points for fitting this effect to data of the given `scales` (the fitter's search
        space, within the physical bounds). Default: the physical bounds, started at the instance's values."""
        return {p.name: (p.lower, p.upper) for p in self.parameters}, [dict(self.values)]

    # -- signals ----------------------------------------------------------------------
    def roles(self) -> tuple[str, ...]:
        return tuple(dict.fromkeys((*self.reads, self.writes)))

    def signal(self, role: str) -> str:
        """The signal name a role is bound to."""
        return self.bind.get(role, role)

    def target(self) -> str:
        """The signal this effect writes."""
        return self.signal(self.writes)

    def _inputs(self, signals: Signals, xp: Any = np) -> dict[str, Array]:
        """The signals of the effect's roles (NumPy: as float arrays; another namespace's as given), an absent
        additive target as zeros."""
        out = {}
        for role, name in self._bound:
            if name in signals:
                out[role] = np.asarray(signals[name], dtype=float) if xp is np else signals[name]
            elif role == self.writes and role not in self.reads:
                out[role] = None  # an additive target starts at zero
            else:
                raise ConfigError(
                    f"effect '{self.name}' needs signal '{name}' (role {role}, {SIGNALS.get(role, ('?', ''))[0]}); "
                    f"available: {', '.join(signals)}"
                )
        if out.get(self.writes) is None:
            ref = next((v for v in out.values() if v is not None), None)
            if ref is None:
                raise ConfigError(f"effect '{self.name}' needs signal '{self.target()}'; available: {', '.join(signals)}")
            out[self.writes] = np.zeros_like(ref, dtype=float) if xp is np else xp.zeros_like(ref)
        return out

    # -- forward models ---------------------------------------------------------------
    def apply(self, signals: Signals, params: Mapping[str, float] | None = None,
              rng: np.random.Generator | None = None) -> np.ndarray:
        """New value of the target signal over whole arrays (time on the last axis)."""
        p = self.resolve(params)
        x = self._inputs(signals)
        if not self.stateful:
            return self._map(x, p, _rng(rng))
        return self._apply_stateful(x, p)

    def evaluate(self, signals: Signals, values: Mapping[str, float]) -> np.ndarray:
        """`apply` with trial `values` (name -> value, over the instance's) taken unchecked: a fitter's
        search may leave the physical bounds where a table's sign convention is unknown."""
        p = {**self.values, **values}
        x = self._inputs(signals)
        return self._apply_stateful(x, p) if self.stateful else self._map(x, p, None if not self.random else _rng(None))

    def init_state(self, sample: Signals, params: Mapping[str, float] | None = None, xp: Any = np) -> dict[str, Any]:
        """State before the first step, from the first sample (batch-shaped arrays of namespace `xp`)."""
        return self._init(self._inputs(sample, xp), self.resolve(params), xp) if self.stateful else {}

    def step(self, state: dict[str, Any], sample: Signals, dt: float,
             params: Mapping[str, float] | None = None, rng: np.random.Generator | None = None) -> np.ndarray:
        """New value of the target at one time step of length dt (s); updates `state` in place (`advance`).

        With `params=None` the instance's values are used unchecked (the fast path for simulators).
        """
        value, new = self.advance(state, sample, dt, None if params is None else self.resolve(params), rng)
        state.update(new)
        return value

    def advance(self, state: dict[str, Any], sample: Signals, dt: float, values: Mapping[str, Any] | None = None,
                rng: Any = None, xp: Any = np, options: StepOptions = EXACT) -> tuple[Array, dict[str, Any]]:
        """One time step of length dt (s) as a function: (new value of the target, new state); `state` is not
        changed, and the new one may hold the sample's arrays (do not change them in place). `values`: every
        parameter's value, taken unchecked (None: the instance's; the `batch_params` may be arrays of the batch
        shape); `xp`: the namespace of the sample's arrays (NumPy, or `array_api_compat`'s torch); `rng`: a random
        effect's stream (anything with `standard_normal(shape)`); `options`: a differentiable simulator's departures
        (`StepOptions`)."""
        p = self.values if values is None else values
        x = self._inputs(sample, xp)
        if not self.stateful:
            return self._map(x, p, _rng(rng) if self.random else rng, xp, options), state
        return self._advance(state, x, dt, p, xp, options)

    def _map(self, x: dict[str, Array], p: dict[str, float], rng: Any, xp: Any = np,
             options: StepOptions = EXACT) -> Array:
        raise NotImplementedError(f"{type(self).__name__} is stateful; use step or apply")

    def _init(self, x: dict[str, Array], p: dict[str, float], xp: Any = np) -> dict[str, Any]:
        raise NotImplementedError

    def _advance(self, state: dict[str, Any], x: dict[str, Array], dt: float, p: dict[str, float], xp: Any = np,
                 options: StepOptions = EXACT) -> tuple[Array, dict[str, Any]]:
        raise NotImplementedError

    def _apply_stateful(self, x: dict[str, np.ndarray], p: dict[str, float]) -> np.ndarray:
        raise NotImplementedError

    # -- description ------------------------------------------------------------------
    def describe(self) -> dict[str, Any]:
        """JSON-ready description (for a simulated file's metadata)."""
        return {
            "name": self.name,
            "effect": self.key,
            "enabled": self.enabled,
            "summary": self.summary,
            "reads": [self.signal(r) for r in self.reads],
            "writes": self.target(),
            "parameters": {
                p.name: {"value": self.values[p.name], "unit": p.unit, "bounds": [p.lower, p.upper], "doc": p.doc}
                for p in self.parameters
            },
        }

    def __repr__(self) -> str:
        vals = ", ".join(f"{k}={v:g}" for k, v in self.values.items())
        state = "" if self.enabled else ", off"
        return f"{type(self).__name__}({self.name!r}{', ' if vals else ''}{vals}{state})"


def _rng(rng: np.random.Generator | None) -> np.random.Generator:
    return rng if rng is not None else np.random.default_rng(0)


def time_steps(time: np.ndarray) -> np.ndarray:
    """dt per sample (s) along the last axis; the first sample gets dt = 0."""
    time = np.asarray(time, dtype=float)
    dt = np.diff(time, axis=-1, prepend=time[..., :1])
    return dt


def rows(*arrays: np.ndarray) -> list[tuple[list[float], ...]]:
    """Broadcast arrays, flatten leading axes, and return per-row Python lists (fast scalar loops)."""
    b = np.broadcast_arrays(*arrays)
    n = b[0].shape[-1]
    flat = [a.reshape(-1, n) for a in b]
    return [tuple(f[i].tolist() for f in flat) for i in range(flat[0].shape[0])]


def uniform_step(time: np.ndarray) -> float | None:
    """The sample interval (s) when `time` (1-D) is uniformly sampled to 1e-9 relative, else None."""
    time = np.asarray(time, dtype=float)
    if time.ndim != 1 or time.size < 2:
        return None
    dt = np.diff(time)
    return float(dt.mean()) if np.ptp(dt) <= 1e-9 * abs(dt.mean()) else None


def lowpass_uniform(x: np.ndarray, dt: float, tau: float) -> np.ndarray:
    """First-order lag of x (time last) with time constant tau (s) at a uniform sample interval dt (s),
    starting at x[..., 0]: the recursion of `lowpass` as one linear filter (`scipy.signal.lfilter`)."""
    x = np.asarray(x, dtype=float)
    a = math.exp(-dt / tau)
    y, _ = lfilter([1.0 - a], [1.0, -a], x, axis=-1, zi=a * x[..., :1])
    return y


def lowpass(x: np.ndarray, time: np.ndarray, tau: float) -> np.ndarray:
    """First-order lag y' = (x - y) / tau (tau s) along the last axis, y starting at x[..., 0].

    Discretised exactly for x held over each step: y_n = y_{n-1} + (x_n - y_{n-1})(1 - exp(-dt_n/tau)).
    Uniformly sampled records go through `lowpass_uniform` (the same recursion, vectorised).
    """
    x = np.asarray(x, dtype=float)
    dt = uniform_step(time)
    if dt is not None:
        return lowpass_uniform(np.broadcast_to(x, np.broadcast_shapes(x.shape, np.shape(time))), dt, tau)
    shape = np.broadcast_shapes(x.shape, np.shape(time))
    out = np.empty(shape)
    out_rows = out.reshape(-1, shape[-1])
    for i, (xs, dts) in enumerate(rows(x, time_steps(time))):
        y = xs[0]
        ys = []
        for xv, dt in zip(xs, dts):
            y += (xv - y) * (1.0 - math.exp(-dt / tau))
            ys.append(y)
        out_rows[i] = ys
    return out
