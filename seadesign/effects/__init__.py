"""The shared effect library: each physical effect once, used by the simulators and the fitter.

An effect (see `base.Effect`) has a `name`, a library `key`, documented `parameters`
(`Param`: name, unit, default, physical bounds), an on/off switch `enabled`, the signals it
`reads` and the one it `writes`, and one forward model used two ways:

    effect.apply(signals, params=None, rng=None) -> ndarray      # whole arrays, time last
    state = effect.init_state(sample); effect.step(state, sample, dt)  # time stepping

`EffectChain` orders effects and runs them (`run` over arrays, `start`/`step` in time).
Signals and units: `SIGNALS`. Library (key -> class): `LIBRARY`.

Torque path:  dead_band (also `backlash`), spring, stiffness_scale, cubic_stiffening,
              hysteresis (Dahl), viscoelastic (standard linear solid), thermal_softening
              (dissipated energy), temperature_softening (measured temperature)
Link loads:   gravity, ground_contact, friction (Coulomb + viscous)
Sensors:      sensor_offset, sensor_drift, sensor_delay, sensor_noise, quantisation, angle_wrap

Example, "data with an undeclared effect": simulate with a chain holding A and B, explain with
a chain holding only A (`chain.configure("B", enabled=False)`).
"""

from seadesign.effects.base import SIGNALS, Effect, Param, lowpass
from seadesign.effects.chain import EffectChain, effect_rng
from seadesign.effects.load import Friction, GravityLoad, StanceLoad
from seadesign.effects.sensor import AngleWrap, Quantisation, SensorDelay, SensorDrift, SensorNoise, SensorOffset
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
        SensorOffset, SensorDrift, SensorDelay, SensorNoise, Quantisation, AngleWrap,
    )
}

__all__ = [
    "LIBRARY", "SIGNALS", "AngleWrap", "CubicStiffening", "DahlHysteresis", "DeadBand", "Effect",
    "EffectChain", "Friction", "GravityLoad", "LinearSpring", "Param", "Quantisation", "SensorDelay",
    "SensorDrift", "SensorNoise", "SensorOffset", "StanceLoad", "StiffnessScale", "TemperatureSoftening",
    "ThermalSoftening", "Viscoelastic", "effect_rng", "lowpass",
]
