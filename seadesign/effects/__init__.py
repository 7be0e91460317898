"""The shared effect library: each physical effect once, used by the simulators and the fitter.

An effect (see `base.Effect`) has a `name`, a library `key`, documented `parameters`
(`Param`: name, unit, default, physical bounds), an on/off switch `enabled`, the signals it
`reads` and the one it `writes`, the `signature` it leaves in a residual, and one forward model
used two ways:

    effect.apply(signals, params=None, rng=None) -> ndarray      # whole arrays, time last (vectorised)
    state = effect.init_state(sample); effect.step(state, sample, dt)  # time stepping

What a fitter needs besides: `search(scales)` (bounds and start points that depend on the data,
`Scales`), `log_params` (positive scale parameters searched in log space), `evaluate` (apply with
unchecked trial values), and the inverse pieces of the compliance direction (`solve_cubic`, `dahl_in_series`,
`sls_deflection`, `softening_marched`, `DeadBand.free_travel`, `EffortLag.torque_from_effort`,
`SpringCurve.rotation`).

`EffectChain` orders effects and runs them (`run` over arrays, `start`/`step` in time).
Signals and units: `SIGNALS`. Library (key -> class): `LIBRARY`.

Torque path:  dead_band (also `backlash`), spring (or spring_curve: the large-deflection torque
              curve), stiffness_scale, cubic_stiffening, hysteresis (Dahl), viscoelastic
              (standard linear solid), thermal_softening (dissipated energy), temperature_softening
              (measured temperature)
Link loads:   gravity, ground_contact, friction (Coulomb + viscous; bound to the motor side and the
              effort it is gear friction)
Sensors:      sensor_offset, sensor_step, sensor_drift, sensor_delay, sensor_noise, quantisation,
              angle_wrap, effort_lag (the servo's current-based effort)

Example, "data with an undeclared effect": simulate with a chain holding A and B, explain with
a chain holding only A (`chain.configure("B", enabled=False)`).
"""

from seadesign.effects.base import SIGNALS, Effect, Param, Scales, lowpass, lowpass_uniform
from seadesign.effects.chain import EffectChain, effect_rng
from seadesign.design.spring import CurveRangeError, TorqueCurve
from seadesign.effects.curve import SpringCurve, spring_law
from seadesign.effects.load import Friction, GravityLoad, StanceLoad
from seadesign.effects.sensor import (
    AngleWrap,
    EffortLag,
    Quantisation,
    SensorDelay,
    SensorDrift,
    SensorNoise,
    SensorOffset,
    SensorStep,
)
from seadesign.effects.spring import (
    CubicStiffening,
    DahlHysteresis,
    DeadBand,
    LinearSpring,
    StiffnessScale,
    TemperatureSoftening,
    ThermalSoftening,
    Viscoelastic,
)

LIBRARY: dict[str, type[Effect]] = {
    cls.key: cls
    for cls in (
        DeadBand, LinearSpring, StiffnessScale, CubicStiffening, DahlHysteresis, Viscoelastic,
        ThermalSoftening, TemperatureSoftening, Friction, GravityLoad, StanceLoad,
        SensorOffset, SensorStep, SensorDrift, SensorDelay, SensorNoise, Quantisation, AngleWrap, EffortLag,
    )
}

__all__ = [
    "LIBRARY", "SIGNALS", "AngleWrap", "CubicStiffening", "CurveRangeError", "DahlHysteresis", "DeadBand", "Effect",
    "EffectChain", "EffortLag", "Friction", "GravityLoad", "LinearSpring", "Param", "Quantisation", "Scales",
    "SensorDelay", "SensorDrift", "SensorNoise", "SensorOffset", "SensorStep", "SpringCurve", "StanceLoad",
    "StiffnessScale", "TemperatureSoftening", "ThermalSoftening", "TorqueCurve", "Viscoelastic", "effect_rng",
    "lowpass", "lowpass_uniform", "spring_law",
]
