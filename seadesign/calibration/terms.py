"""Where each library effect acts in the loop's model, and the model's evaluation over whole records.

A `Term` is a named library effect (`seadesign.effects`) in a model; its parameters are the
effect's, with the effect's names and units. `PLACES` says where an effect acts:

- `sensor`: on the measured reading (or, with `sensor_on="deflection"`, on the deflection reading
  the model reads, undone there): offset, step, drift, delay;
- `effort` (compliance direction with an effort signal): the servo's effort is undone into the
  spring torque: its lag (`EffortLag.torque_from_effort`) and the gear friction on the motor side;
- `deflection`: dead-band or backlash (`DeadBand`; in the compliance direction its free travel);
- `spring`: the spring law: `stiffness_scale` (the declared k, always refitted), the law's shape on a bench with a
  torque curve (`mooney_rivlin`, `yeoh`: the curve of the spring's own part under that law, `loop.law_family`), cubic stiffening,
  hysteresis, viscoelasticity (torque terms; in the compliance direction inverted: a Newton solve of
  the cubic, the inverse of the standard-linear-solid filter, the Dahl loop sharing the torque with k), thermal and
  temperature softening (factors; thermal in the compliance direction marched in time);
- `load` (stiffness direction): friction against `velocity`, gravity against `angle`;
- `torque_channel` (a bench in the stiffness direction): the torque sensor's channel lags the deflection's,
  a pure delay (`torque_delay`: `SensorDelay` on the torque, the torque behind the deflection; the deflection
  behind the torque is the deflection reading's `sensor_delay`) or a first-order low-pass such as a filtered
  load-cell amplifier (`torque_lag`: `EffortLag`'s filter on the torque). The same library effects as on
  their default channels (`TORQUE_CHANNEL`), applied to the predicted torque.

A spring model (bench, robot) reads its input (deflection; torque or effort, with the friction taken off
it) through the zero-phase Savitzky-Golay smoother (`LoopData.smooth`, ~0.1 s): the input's noise would
otherwise let any filter-like effect (a fractional-sample shift, a fast relaxation, a rate term) lower
the error by averaging that noise and be named for it. On a generic table stateful effects read the
smoothed deflection (noise would act as many tiny reversals) and a delay shifts the smoothed prediction
and adds the change. The fitter's filters run at the median sample interval.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.ndimage import shift

from seadesign.effects import LIBRARY, Effect
from seadesign.effects.base import lowpass
from seadesign.effects.spring import dahl, dahl_in_series, sls_deflection, softening_marched, solve_cubic
from seadesign.calibration.table import LoopData

PLACES: dict[str, str] = {
    "sensor_delay": "sensor", "sensor_offset": "sensor", "sensor_step": "sensor", "sensor_drift": "sensor",
    "effort_lag": "effort", "friction": "load", "dead_band": "deflection",
    "stiffness_scale": "spring", "mooney_rivlin": "spring", "yeoh": "spring", "cubic_stiffening": "spring", "hysteresis": "spring", "viscoelastic": "spring",
    "thermal_softening": "spring", "temperature_softening": "spring", "gravity": "load",
}
#: order of the effects within the model (the simulator's order in its chain)
ORDER = ("effort_lag", "friction", "dead_band", "stiffness_scale", "mooney_rivlin", "yeoh", "cubic_stiffening", "hysteresis", "viscoelastic",
         "thermal_softening", "temperature_softening", "gravity", "sensor_delay", "sensor_offset", "sensor_step",
         "sensor_drift")
#: loop candidates that are a library effect on a bench's torque channel: name -> (library key, binding)
TORQUE_CHANNEL = {"torque_delay": ("sensor_delay", {"hall": "torque"}), "torque_lag": ("effort_lag", {"effort": "torque"})}
#: effects the loop can trace as candidates (library keys, and the torque-channel names); the spring itself is
#: declared, not traced
#: loop candidates that are the spring law's shape (`LoopData.shapes`: only where the spring's part is known)
LAW_SHAPES = ("mooney_rivlin", "yeoh")
CANDIDATES = tuple(k for k in ORDER if k != "stiffness_scale" and k not in LAW_SHAPES) + tuple(TORQUE_CHANNEL)
#: effects whose value at a sample needs the whole record (history or neighbours: the smoothed friction, the
#: sensor effects undone before smoothing); a model without them is evaluated on the fitted rows alone
WHOLE_RECORD = frozenset({"hysteresis", "viscoelastic", "thermal_softening", "sensor_delay"})


def whole_record(terms: list[Term], data: LoopData) -> bool:
    """Whether `terms` on `data` need the whole record (else the fitted rows alone will do)."""
    keys = {t.key for t in terms}
    sensors = {k for k, v in PLACES.items() if v == "sensor"}
    return bool(keys & WHOLE_RECORD) or any(t.on_torque for t in terms) or \
        (data.direction == "compliance" and "friction" in keys) or \
        (data.sensor_on == "deflection" and data.spring is not None and bool(keys & sensors))


@dataclass(frozen=True)
class Term:
    """A library effect in a model under a unique `name`; `declared`: given by the model (spring.json or
    the actuator data), so refitted from its values and tested for support, rather than traced."""

    name: str
    effect: Effect
    declared: bool = False
    on_torque: bool = False  # a sensor effect of the bench's torque channel (`TORQUE_CHANNEL`)

    @property
    def key(self) -> str:
        return self.effect.key

    @property
    def candidate(self) -> str:
        """The loop candidate this term is: its library key, or its torque-channel name."""
        return self.name if self.on_torque else self.key

    @classmethod
    def of(cls, candidate: str) -> "Term":
        """A fresh term of a loop candidate (`CANDIDATES`) at its library defaults."""
        if candidate in TORQUE_CHANNEL:
            key, bind = TORQUE_CHANNEL[candidate]
            return cls(candidate, LIBRARY[key](candidate, bind=bind), on_torque=True)
        return cls(candidate, LIBRARY[candidate]())


def place(term: Term, data: LoopData) -> str:
    """Where `term` acts on `data`: in the compliance direction friction is taken off the torque input (gear
    friction off the effort, against the motor velocity; a bench's friction against the deflection rate)."""
    if term.on_torque:
        return "torque_channel"
    if term.key == "friction" and data.direction == "compliance":
        return "effort"
    return PLACES[term.key]


def applicable(key: str, data: LoopData) -> bool:
    """Whether the library effect `key` can act on `data` (its signals are there, its place exists)."""
    s, comp = data.signals, data.direction == "compliance"
    need = {
        "effort_lag": comp and "effort" in s,
        "friction": ("motor_velocity" in s or "velocity" in s) if comp else "velocity" in s,
        "gravity": not comp and "angle" in s,
        "temperature_softening": "temperature" in s,
        "stiffness_scale": data.spring is not None or np.ptp(data.predicted) > 0,
        **dict.fromkeys(TORQUE_CHANNEL, not comp and data.sensor_on == "deflection" and data.spring is not None),
        **{k: not comp and k in data.shapes for k in LAW_SHAPES},
    }
    spring_terms = ("dead_band", "cubic_stiffening", "hysteresis", "viscoelastic", "thermal_softening")
    if key in spring_terms:
        return comp or "deflection" in s
    return need.get(key, key in LIBRARY)


def ordered(terms: list[Term]) -> list[Term]:
    return sorted(terms, key=lambda t: ORDER.index(t.key))


def predict(data: LoopData, terms: list[Term], values: dict[str, dict[str, float]]) -> np.ndarray:
    """The model's prediction of `data.measured` with `terms` at `values` (term name -> parameter -> value)."""
    terms = ordered(terms)
    at = {p: [t for t in terms if place(t, data) == p]
          for p in ("sensor", "effort", "deflection", "spring", "load", "torque_channel")}
    if data.direction == "compliance":
        y = (0.0 if data.base is None else data.base) + data.sign * _deflection(data, at, values)
    else:
        y = _torque(data, at, values)
        for t in at["torque_channel"]:  # the torque sensor's channel behind the deflection's
            p = values[t.name]
            y = shift(y, p["delay_s"] / data.dt, order=3, mode="nearest") if t.key == "sensor_delay" else \
                lowpass(y, data.time, p["time_constant_s"])
    if data.sensor_on == "measured":
        for t in at["sensor"]:
            y = _delayed(data, y, values[t.name]["delay_s"]) if t.key == "sensor_delay" else \
                t.effect.evaluate({"hall": y, "time": data.time}, values[t.name])
    return y


def _delayed(data: LoopData, y: np.ndarray, delay_s: float) -> np.ndarray:
    """y(t - delay_s): the smoothed y shifted plus the raw y's own noise, so a fraction of a sample cannot
    average the noise away; a negative delay advances. The shift is a cubic-spline interpolation at the median
    sample interval (`scipy.ndimage.shift`): smooth in the delay, where linear interpolation has a kink at every
    whole sample that stops a least-squares search there."""
    ys = data.smoothed(y)
    return y + shift(ys, delay_s / data.dt, order=3, mode="nearest") - ys


def _sensor_inverse(data: LoopData, terms: list[Term], values, d: np.ndarray) -> np.ndarray:
    """The true deflection from a reading with the sensor effects `terms`: each undone, last first."""
    for t in reversed(terms):
        p = values[t.name]
        if t.key == "sensor_delay":
            d = _delayed(data, d, -p["delay_s"])
        else:  # additive: offset, step, drift with the opposite sign
            d = t.effect.evaluate({"hall": d, "time": data.time}, {k: (-v if k != "time_s" else v) for k, v in p.items()})
    return d


def _path(data: LoopData, d: np.ndarray) -> np.ndarray:
    """The spring path at deflection d: the spring's torque, or on a generic table the slope times d."""
    if data.spring is not None:
        return data.spring.apply({"deflection": d})
    return data.gain * d


def _torque(data: LoopData, at: dict[str, list[Term]], values) -> np.ndarray:
    """Stiffness direction: deflection -> (sensor undone) -> dead-band -> spring law -> + loads."""
    signals = data.signals
    spring = data.spring is not None  # a spring's deflection input is read through the smoother
    d0 = data.smooth("deflection") if spring else signals.get("deflection")
    path0 = data.predicted if data.predicted is not None else _path(data, d0)
    deflection, path = d0, path0
    if data.sensor_on == "deflection" and at["sensor"]:
        deflection = _sensor_inverse(data, at["sensor"], values, signals["deflection"])
        deflection = data.smoothed(deflection) if spring else deflection
        path = path0 + _path(data, deflection) - _path(data, d0)
    for t in at["deflection"]:
        banded = t.effect.evaluate({"deflection": deflection}, values[t.name])
        path, deflection = path + _path(data, banded) - _path(data, deflection), banded
    stateful = {"hysteresis", "viscoelastic", "thermal_softening"} & {t.key for t in at["spring"]}
    ds = None if not stateful else deflection if spring else \
        data.smoothed(deflection) if deflection is not d0 else data.smooth("deflection")
    tau, factor = path, 1.0
    scale = next((values[t.name]["scale"] for t in at["spring"] if t.key == "stiffness_scale"), 1.0)
    for t in at["spring"]:
        p = values[t.name]
        if t.key == "stiffness_scale":
            tau = tau * p["scale"]
        elif t.key in LAW_SHAPES:
            tau = tau + scale * t.effect.shape_torque(deflection, p[t.effect.parameters[0].name])
        elif t.key == "cubic_stiffening":
            tau = tau + p["k3_Nm_per_rad3"] * deflection ** 3
        elif t.key == "hysteresis":
            tau = tau + dahl(ds, p["torque_Nm"], p["stiffness_Nm_per_rad"])
        elif t.key == "viscoelastic":  # k2 (d - relaxed): the relaxed state from the smoothed deflection
            arm = t.effect.evaluate({"deflection": ds, "time": data.time, "torque": np.zeros_like(ds)}, p)
            tau = tau + arm + p["maxwell_stiffness_Nm_per_rad"] * (deflection - ds)
        elif t.key == "thermal_softening":
            factor = factor * _thermal_factor(data, p, lambda: path * np.diff(ds, prepend=ds[0]))
        else:  # temperature_softening
            factor = factor * t.effect.evaluate({"temperature": signals["temperature"], "torque": np.ones(data.n)}, p)
    y = tau * factor + ((data.predicted - path0) if data.predicted is not None else 0.0)
    for t in at["load"]:
        y = t.effect.evaluate({**signals, "load_torque": y}, values[t.name])
    return y


def _thermal_factor(data: LoopData, p: dict[str, float], work) -> np.ndarray:
    """Thermal softening's stiffness factor: from a measured `energy` signal, else marched from `work()`."""
    if "energy" in data.signals:
        e = data.signals["energy"]
        return np.maximum(1.0 - p["softening_per_J"] * (e - e[0]), 0.05)
    return softening_marched(np.abs(work()), data.dt, p["softening_per_J"], p["cooling_time_s"],
                             data.direction == "compliance")


def spring_torque(data: LoopData, at: dict[str, list[Term]], values) -> np.ndarray:
    """Compliance direction: the spring torque from the torque or effort signal, the effort's lag and gear
    friction undone, through the zero-phase smoother (module docstring)."""
    role = "torque" if "torque" in data.signals else "effort"
    tau = data.smooth(role)
    for t in at["effort"]:
        p = values[t.name]
        if t.key == "effort_lag":
            tau = tau + p["time_constant_s"] * data.rate("effort")
        else:  # friction on the motor side (gear friction in the effort), or against a bench's deflection rate
            e = t.effect
            v = data.signals["motor_velocity" if "motor_velocity" in data.signals else "velocity"]
            tau = tau - data.smoothed(e.evaluate({e.signal("velocity"): v, e.signal("load_torque"): np.zeros(data.n)}, p))
    return tau


def _deflection(data: LoopData, at: dict[str, list[Term]], values) -> np.ndarray:
    """Compliance direction: torque -> spring law inverted -> deflection -> free travel of the dead-band."""
    tau = spring_torque(data, at, values)
    spring = [t for t in at["spring"] if t.key == "stiffness_scale"]
    scale = values[spring[0].name]["scale"] if spring else 1.0
    k = data.gain * scale
    curve = hasattr(data.spring, "curve")
    # a fitter's trial may push the torque past the curve's end: held there (the data's range is checked up front)
    xs = x = data.spring.rotation(tau, scale, clamp=True) if curve else tau / k
    for t in at["spring"]:
        p = values[t.name]
        if t.key == "cubic_stiffening":  # k d + k3 d^3 = k x
            x = solve_cubic(x, p["k3_Nm_per_rad3"] / k)
        elif t.key == "hysteresis":
            x = x - dahl_in_series(xs, p["torque_Nm"], p["stiffness_Nm_per_rad"], k) / k
        elif t.key == "viscoelastic":
            x = x + sls_deflection(xs, data.dt, p["maxwell_stiffness_Nm_per_rad"] / k, p["relaxation_time_s"]) - xs
        elif t.key == "thermal_softening":
            x = x / _thermal_factor(data, p, lambda: tau * np.diff(xs, prepend=xs[0]))
        elif t.key == "temperature_softening":
            x = x / t.effect.evaluate({"temperature": data.signals["temperature"], "torque": np.ones(data.n)}, p)
    for t in at["deflection"]:  # the free travel, its side as uncertain as the smoothed torque
        noise = data.noise("torque" if "torque" in data.signals else "effort") / k
        x = x + t.effect.free_travel(xs, values[t.name]["width_rad"], noise) - xs
    return x
