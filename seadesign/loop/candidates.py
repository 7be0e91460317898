"""Candidate effects: small parametric models with physical meaning and units, built over signal roles.

Each `Candidate` maps (data, parameters, value) -> new value. Candidates of the torque path
(stages below `LOAD_STAGE`) act on the path term of the prediction (the part that passes
through the spring, see `LoopData.path`); the others act on the whole prediction. In the
compliance direction (the path is a deflection computed as torque / k) a spring-torque term
enters divided by k, so its parameters are relative to k (hysteresis tau_h / k and sigma / k,
viscoelastic k2 / k, cubic k3 / k), softening divides the path, and thermal softening takes its
heat from the `torque` signal. Cubic stiffening and the viscoelastic arm are inverted exactly
there (a Newton solve of the cubic, the inverse of the standard-linear-solid filter). The forward
models are those of the shared effect library (`seadesign.effects`) where its form fits the
fit: dead-band, temperature softening and gravity call the library's effect
objects. The rest are written here because the fit needs what the library does not offer:
signed coefficients (friction, offset, drift, a measured-side delay of either sign), Dahl hysteresis solved
in closed form over blocks of samples instead of a per-sample Python loop (`dahl`, equal to the library's), a
vectorised standard-linear-solid lag (`scipy.signal.lfilter` at the median sample interval)
and thermal softening driven by dissipated energy with one identifiable gain (1/J, the
library's softening_per_K x loss_factor / heat_capacity).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import numpy as np
from scipy.signal import lfilter, lfilter_zi

from seadesign.effects import DeadBand, GravityLoad, Param, TemperatureSoftening
from seadesign.loop.table import LoopData, smooth

LOAD_STAGE = 7  # stages below act on the path term; from here on the whole prediction

Apply = Callable[[LoopData, np.ndarray, np.ndarray], np.ndarray]


@dataclass(frozen=True)
class Candidate:
    """One effect the loop can add: key, meaning, roles it needs, stage order, parameters, starts, model."""

    key: str
    summary: str
    signature: str
    roles: tuple[str, ...]
    stage: int
    params: Callable[[LoopData], tuple[Param, ...]]
    starts: Callable[[LoopData], list[list[float]]]
    apply: Apply
    log: tuple[int, ...] = ()  # indices of positive scale parameters fitted in log space
    compliance_roles: tuple[str, ...] = ()  # further roles needed in the compliance direction

    def applicable(self, data: LoopData) -> bool:
        roles = self.roles + (self.compliance_roles if data.direction == "compliance" else ())
        return all(r in data.signals for r in roles)


def _span(data: LoopData) -> float:
    return float(np.ptp(data.measured)) or 1.0


def _dmax(data: LoopData) -> float:
    return float(np.max(np.abs(data.signals["displacement"]))) or 1.0


def _g(data: LoopData) -> float:
    return float(data.gain or 1.0)


def _u(data: LoopData, role: str) -> str:
    return data.unit(role)


# -- torque path --------------------------------------------------------------------------
def _dead_band(data, th, path):
    d, b = data.signals["displacement"], th[0]
    if data.direction == "stiffness":
        return path + _g(data) * (DeadBand().apply({"deflection": d}, {"width_rad": b}) - d)
    return path + _g(data) * np.sign(d) * 0.5 * b  # free travel added to a deflection computed from torque


def _scale(data, th, path):
    return path * (th[0] if data.direction == "stiffness" else 1.0 / th[0])


def solve_cubic(x: np.ndarray, r: float, iterations: int = 12) -> np.ndarray:
    """d with d + r d^3 = x elementwise (Newton from d = x); for r < 0 d stays within the turning
    points +-1/sqrt(-3 r), beyond which no deflection carries the torque."""
    d = np.array(x, dtype=float)
    turn = 1.0 / math.sqrt(-3.0 * r) if r < 0 else math.inf
    for _ in range(iterations):
        d = d - (d + r * d ** 3 - x) / np.maximum(1.0 + 3.0 * r * d * d, 1e-3)
        if r < 0:
            d = np.clip(d, -turn, turn)
    return d


def _cubic(data, th, path):
    x = data.signals["displacement"]
    if data.direction == "stiffness":
        return path + th[0] * x ** 3
    return path + _g(data) * (solve_cubic(x, th[0]) - x)  # k d + k3 d^3 = k x, th[0] = k3 / k


def dahl(d: np.ndarray, torque: float, stiffness: float, block: int = 16) -> np.ndarray:
    """Dahl hysteresis torque z (unit of `torque`) along a displacement record, vectorised.

    The same recursion as `seadesign.effects.DahlHysteresis` (z_n = a_n z_{n-1} + (1 - a_n) s_n tau_h,
    a_n = exp(-sigma |dd_n| / tau_h)), solved in closed form within blocks of `block` samples
    (all blocks at once) and carried from block to block. Each sample's decay exponent is capped
    at 40 (a_n < 5e-18 either way), so a block's exponents stay below 640 and finite.
    """
    n = d.size
    step = np.diff(d, prepend=d[0])
    decay = np.abs(step) * (stiffness / torque)
    b = np.sign(step) * torque * -np.expm1(-decay)
    pad = -n % block
    v = np.cumsum(np.pad(np.minimum(decay, 40.0), (0, pad)).reshape(-1, block), axis=1)
    local = np.exp(-v) * np.cumsum(np.pad(b, (0, pad)).reshape(-1, block) * np.exp(v), axis=1)
    carry, into = 0.0, []
    for end, fade in zip(local[:, -1].tolist(), np.exp(-v[:, -1]).tolist()):
        into.append(carry)
        carry = end + carry * fade
    return (local + np.asarray(into)[:, None] * np.exp(-v)).ravel()[:n]


def _add(data: LoopData, path: np.ndarray, term: np.ndarray) -> np.ndarray:
    """Add a spring-torque term to the path: in the stiffness direction `term` is a torque (measured
    unit); in the compliance direction it is that torque over k (displacement unit), which the true
    deflection lacks: (torque - term k) / k = displacement - term, times the path's gain."""
    return path + term if data.direction == "stiffness" else path - _g(data) * term


def _hysteresis(data, th, path):
    return _add(data, path, dahl(data.smooth("displacement"), th[0], th[1]))


def lowpass_uniform(x: np.ndarray, dt: float, tau: float) -> np.ndarray:
    """First-order lag of x with time constant tau (s) at sample interval dt (s), starting at x[0]."""
    a = math.exp(-dt / tau)
    y, _ = lfilter([1.0 - a], [1.0, -a], x, zi=[a * x[0]])
    return y


def _viscoelastic(data, th, path):
    x = data.smooth("displacement")
    if data.direction == "stiffness":
        return path + th[0] * (x - lowpass_uniform(x, data.dt, th[1]))
    # x = torque / k = d + r (d - lowpass(d)), r = k2 / k: invert the filter for the deflection d
    r, a = th[0], math.exp(-data.dt / th[1])
    b, den = [1.0, -a], [1.0 + r * a, -a * (1.0 + r)]
    d, _ = lfilter(b, den, x, zi=lfilter_zi(b, den) * x[0])
    return path + _g(data) * (d - x)


def leaky_sum(h: np.ndarray, dt: float, tau: float) -> np.ndarray:
    """s_n = s_{n-1} exp(-dt/tau) + h_n at sample interval dt (s): heat with cooling time tau (s)."""
    a = math.exp(-dt / tau)
    return lfilter([1.0], [1.0, -a], h)


def _soften(data: LoopData, path: np.ndarray, factor: np.ndarray) -> np.ndarray:
    """Stiffness times `factor`: the torque path scales by it, a deflection path by its inverse."""
    return path * factor if data.direction == "stiffness" else path / factor


def softening_from_compliance(x: np.ndarray, torque: np.ndarray, dt: float, c: float, tc: float,
                              chunk: int = 25) -> np.ndarray:
    """Stiffness factor f per sample when only torque (Nm) and x = torque / k (rad) are known.

    The spring heats by |k d dd| with the true deflection d = x / f, i.e. by q / f^2 with
    q = |torque dx|, and f = 1 - c H with H the heat (J) cooling with time constant tc (s). H
    depends on f, which a whole-record fixed point cannot resolve once softening passes a third,
    so the record is marched in chunks of `chunk` samples with f constant in each, solved
    implicitly (Newton on f = 1 - c (H_start a^m + S / f^2)); f is floored at 0.05.
    """
    a = math.exp(-dt / tc)
    q = np.abs(torque * np.diff(x, prepend=x[0]))
    filled = lfilter([1.0], [1.0, -a], q)
    ends = np.append(np.arange(chunk - 1, x.size - 1, chunk), x.size - 1)
    per_chunk = np.empty(ends.size)
    heat, f, prev = 0.0, 1.0, -1
    for j, e in enumerate(ends):
        decay = a ** (e - prev)
        start = heat * decay
        gained = filled[e] - (decay * filled[prev] if prev >= 0 else 0.0)
        for _ in range(8):
            slope = 1.0 - 2.0 * c * gained / f ** 3
            if slope <= 0.0:  # past the turning point: no stiffness carries this heat, the spring runs away
                f = 0.05
                break
            change = (f - 1.0 + c * (start + gained / f ** 2)) / slope
            f = min(max(f - change, 0.05), 1.0)
            if abs(change) < 1e-12:
                break
        heat, prev = start + gained / f ** 2, e
        per_chunk[j] = f
    f_chunk = np.repeat(per_chunk, np.diff(np.concatenate([[-1], ends])))
    return np.maximum(1.0 - c * lfilter([1.0], [1.0, -a], q / f_chunk ** 2), 0.05)


def _thermal(data, th, path):
    if "energy" in data.signals:
        return _soften(data, path, np.maximum(1.0 - th[0] * (data.signals["energy"] - data.signals["energy"][0]), 0.05))
    x = data.smooth("displacement")
    if data.direction == "stiffness":
        heat = leaky_sum(np.abs(path * np.diff(x, prepend=x[0])), data.dt, th[1])
        return path * np.maximum(1.0 - th[0] * heat, 0.05)
    return path / softening_from_compliance(x, data.smooth("torque"), data.dt, th[0], th[1])


def _temperature(data, th, path):
    t = data.signals["temperature"]
    factor = TemperatureSoftening().apply({"temperature": t, "torque": np.ones_like(t)},
                                          {"softening_per_K": th[0], "reference_temperature_C": float(t[0])})
    return _soften(data, path, factor)


# -- loads and sensors on the whole prediction --------------------------------------------
def _friction(data, th, y):
    v = data.signals["velocity"]
    return y + th[0] * np.tanh(v / th[2]) + th[1] * v


def _gravity(data, th, y):
    return GravityLoad().apply({"angle": data.signals["angle"], "load_torque": y},
                               {"amplitude_Nm": th[0], "angle_offset_rad": th[1]})


def _offset(data, th, y):
    return y + th[0]


def _drift(data, th, y):
    return y + th[0] * (data.time - data.time[0])


def _delay(data, th, y):
    # shift the smoothed prediction and add the change, so that at td = 0 the prediction is unchanged
    # and a fractional-sample shift cannot pose as a noise filter on the prediction
    t = data.time
    ys = smooth(y, t)
    return y + np.interp(t - th[0], t, ys) - ys


def _stiff(data: LoopData) -> float:
    """Scale of a spring-torque term's slope: the path's gain (measured unit per displacement unit) in
    the stiffness direction, 1 in the compliance direction (terms there are relative to k)."""
    return abs(_g(data)) if data.direction == "stiffness" else 1.0


def _cubic_params(data: LoopData) -> tuple[Param, ...]:
    du, dmax = _u(data, "displacement"), _dmax(data)
    if data.direction == "stiffness":
        bound = 10 * _span(data) / dmax ** 3
        return (Param("k3", f"{data.measured_unit}/{du}^3", 0.0, -bound, bound, "cubic stiffness coefficient"),)
    return (Param("k3_ratio", f"1/{du}^2", 0.0, -10 / dmax ** 2, 10 / dmax ** 2,
                  "cubic stiffness over k, k3 / k (the deflection solves d + (k3/k) d^3 = torque / k)"),)


def _hysteresis_params(data: LoopData) -> tuple[Param, ...]:
    du = _u(data, "displacement")
    if data.direction == "stiffness":
        return (Param("torque", data.measured_unit, 0.01 * _span(data), 1e-6, min(20.0, _span(data)),
                      "saturation torque tau_h"),
                Param("stiffness", f"{data.measured_unit}/{du}", abs(_g(data)), 1e-3, 1e5,
                      "initial slope sigma after a reversal"))
    return (Param("deflection", du, 0.01 * _dmax(data), 1e-6 * _dmax(data), _dmax(data),
                  "saturation torque over k, tau_h / k"),
            Param("stiffness_ratio", "1", 1.0, 1e-3, 1e5, "initial slope after a reversal over k, sigma / k"))


def _hysteresis_starts(data: LoopData) -> list[list[float]]:
    size = 0.02 * (_span(data) if data.direction == "stiffness" else _dmax(data))
    return [[size, 3 * _stiff(data)], [size, 30 * _stiff(data)]]


def _viscoelastic_params(data: LoopData) -> tuple[Param, ...]:
    tr = Param("relaxation_time", "s", 1.0, 1e-3, 1e3, "relaxation time tr")
    if data.direction == "stiffness":
        return (Param("maxwell_stiffness", f"{data.measured_unit}/{_u(data, 'displacement')}", 0.0, 0.0,
                      10 * abs(_g(data)) + _span(data) / _dmax(data), "stiffness k2 of the Maxwell arm"), tr)
    return Param("maxwell_ratio", "1", 0.0, 0.0, 10.0, "Maxwell arm stiffness over k, k2 / k"), tr


def _vel_scale(data) -> float:
    v = np.abs(data.signals["velocity"])
    return float(np.quantile(v, 0.9)) or 1.0


CANDIDATES: tuple[Candidate, ...] = (
    Candidate(
        "dead_band", "dead zone of total width b in the displacement (spring dead-band or backlash)",
        "flat/S-shape near zero displacement", ("displacement",), 0,
        lambda d: (Param("width", _u(d, "displacement"), 0.0, 0.0, min(0.5, _dmax(d)), "total width b of the dead zone"),),
        lambda d: [[0.05 * _dmax(d)], [0.2 * _dmax(d)]], _dead_band),
    Candidate(
        "stiffness_scale", "true / modelled stiffness (wrong modulus, infill or geometry)",
        "residual proportional to the prediction", ("displacement",), 1,
        lambda d: (Param("scale", "1", 1.0, 0.01, 100.0, "ratio of true to modelled stiffness"),),
        lambda d: [[1.0], [0.1], [10.0]], _scale),
    Candidate(
        "cubic_stiffening", "odd cubic term k3 d^3 (k3 > 0 stiffening, < 0 softening)",
        "odd cubic residual vs displacement", ("displacement",), 2,
        _cubic_params, lambda d: [[0.0]], _cubic),
    Candidate(
        "hysteresis", "Dahl hysteresis: torque z, dz/dd = sigma (1 - z sign(dd) / tau_h)",
        "loop vs displacement that stays open at low frequency", ("displacement",), 3,
        _hysteresis_params, _hysteresis_starts, _hysteresis, log=(0, 1)),
    Candidate(
        "viscoelastic", "standard linear solid: Maxwell arm k2 with relaxation time tr",
        "phase lead; loop that vanishes at low and high frequency", ("displacement",), 4,
        _viscoelastic_params, lambda d: [[0.1 * _stiff(d), tr] for tr in (0.05, 0.5, 5.0)], _viscoelastic, log=(1,)),
    Candidate(
        "thermal_softening", "stiffness x (1 - c H), H = heat from dissipated energy with cooling time tc",
        "drift that tracks cumulative dissipated energy", ("displacement",), 5,
        lambda d: (Param("softening_per_J", "1/J", 0.0, 0.0, 1.0, "relative stiffness loss c per joule of retained heat"),
                   Param("cooling_time", "s", 600.0, 1.0, 1e6, "cooling time constant tc")),
        lambda d: [[1e-3, tc] for tc in (30.0, 300.0, 3000.0)], _thermal, log=(1,), compliance_roles=("torque",)),
    Candidate(
        "temperature_softening", "stiffness x (1 - a (T - T0)), T0 the first sample's temperature",
        "drift that tracks temperature", ("temperature",), 6,
        lambda d: (Param("softening_per_K", "1/K", 0.0, 0.0, 0.05, "relative stiffness loss a per kelvin"),),
        lambda d: [[0.005]], _temperature),
    Candidate(
        "friction", "Coulomb + viscous: Fc tanh(v / vs) + Fv v",
        "jump at v = 0 and slope vs v", ("velocity",), 7,
        lambda d: (Param("coulomb", d.measured_unit, 0.0, -_span(d), _span(d), "Coulomb friction Fc"),
                   Param("viscous", f"{d.measured_unit}/({_u(d, 'velocity')})", 0.0, -100 * _span(d) / _vel_scale(d),
                         100 * _span(d) / _vel_scale(d), "viscous coefficient Fv"),
                   Param("smoothing", _u(d, "velocity"), 0.05 * _vel_scale(d), 1e-4 * _vel_scale(d),
                         _vel_scale(d), "velocity vs below which the Coulomb term fades")),
        lambda d: [[0.01 * _span(d), 0.0, 0.02 * _vel_scale(d)], [0.01 * _span(d), 0.0, 0.2 * _vel_scale(d)]],
        _friction, log=(2,)),
    Candidate(
        "gravity", "gravity load A sin(angle + phi), A = m g l_c",
        "follows the link angle, present at v = 0", ("angle",), 8,
        lambda d: (Param("amplitude", d.measured_unit, 0.0, 0.0, min(100.0, 2 * _span(d)), "m g l_c"),
                   Param("angle_offset", "rad", 0.0, -math.pi, math.pi, "angle phi at which the load vanishes, negated")),
        lambda d: [[0.1 * _span(d), phi] for phi in (-2.0, 0.0, 2.0)], _gravity),
    Candidate(
        "sensor_offset", "constant offset c of the measured channel",
        "mean shift", (), 9,
        lambda d: (Param("offset", d.measured_unit, 0.0, -_span(d), _span(d), "offset c"),),
        lambda d: [[0.0]], _offset),
    Candidate(
        "sensor_drift", "linear drift r (t - t0) of the measured channel",
        "ramp over the recording", ("time",), 10,
        lambda d: (Param("rate", f"{d.measured_unit}/s", 0.0, -10 * _span(d) / np.ptp(d.time),
                         10 * _span(d) / np.ptp(d.time), "drift rate r"),),
        lambda d: [[0.0]], _drift),
    Candidate(
        "sensor_delay", "measured(t) = prediction(t - td); td < 0: the input sensor lags",
        "residual about -td x rate; cross-correlation peak at a non-zero lag", ("time",), 11,
        lambda d: (Param("delay", "s", 0.0, -1.0, 1.0, "delay td of the measured channel behind the prediction"),),
        lambda d: [[td] for td in (-0.1, -0.02, 0.02, 0.1)], _delay),
)

LIBRARY: dict[str, Candidate] = {c.key: c for c in CANDIDATES}
