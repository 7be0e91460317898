"""Simulator settings and the effect chains built from a spring.json.

Everything about the spring, servo and robot comes from spring.json (`load_spring`); the
few quantities it does not hold (P gain, lower-leg mass share and centre of mass, weight
share in stance) are `KneeConfig` fields with units and the reasoning behind the defaults.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any

from seadesign.effects import (
    AngleWrap,
    CubicStiffening,
    DahlHysteresis,
    DeadBand,
    EffectChain,
    EffortLag,
    Friction,
    GravityLoad,
    Quantisation,
    SensorDelay,
    SensorDrift,
    SensorNoise,
    SensorOffset,
    SensorStep,
    StanceLoad,
    StiffnessScale,
    ThermalSoftening,
    Viscoelastic,
    spring_law,
)
from seadesign.design.spring import TorqueCurve, torque_curve
from seadesign.constants import G_M_PER_S2
from seadesign.errors import ConfigError

#: Coulomb friction of the gearbox in the servo's effort (Nm): the thesis's servo reports torque
#: before any torque reaches the horn (Stelter 2022, sec. 6.4, fig. 6.9: the servo must first overcome the
#: gearbox friction); 0.3 Nm is our estimate, declared by the loop's robot model.
GEAR_COULOMB_NM = 0.3


@dataclass(frozen=True)
class KneeConfig:
    """Servo and link data of one knee (SI units).

    The spring, servo limits and robot geometry come from spring.json via `from_spring`;
    the rest are estimates for the Wolfgang-OP: the lower leg with foot and two ankle servos is
    about 8 % of the robot's mass, its centre of mass 75 % of the shank length below the knee;
    walking "with support" (thesis sec. 6.2) puts half the body weight on the legs; in the walk
    pose the hip is flexed by about half the knee angle (0.5 rad), so the hanging shank leans
    knee angle - 0.5 rad from vertical.
    """

    k_Nm_per_rad: float  # small-load stiffness
    stall_torque_Nm: float
    no_load_speed_rad_per_s: float
    backlash_rad: float
    mass_kg: float
    lower_leg_m: float
    upper_leg_m: float
    p_gain_Nm_per_rad: float = 60.0
    torque_limit_Nm: float | None = None  # current limit as torque; None = stall torque
    lower_leg_mass_fraction: float = 0.08
    lower_leg_com_fraction: float = 0.75
    stance_weight_share: float = 0.5
    hip_flexion_rad: float = 0.5
    max_substep_s: float = 0.0025
    torque_curve: TorqueCurve | None = None  # the large-deflection law when spring.json carries it (else k)

    @classmethod
    def from_spring(cls, spring: dict[str, Any], **overrides: Any) -> "KneeConfig":
        act, robot = spring["actuator"], spring["robot"]
        return cls(
            k_Nm_per_rad=spring["k_Nm_per_rad"],
            stall_torque_Nm=act["stall_torque_Nm"],
            no_load_speed_rad_per_s=act["no_load_speed_rad_per_s"],
            backlash_rad=act["backlash_rad"],
            mass_kg=robot["mass_kg"],
            lower_leg_m=robot["lower_leg_m"],
            upper_leg_m=robot["upper_leg_m"],
            torque_curve=torque_curve(spring),
            **overrides,
        )

    @property
    def torque_limit(self) -> float:
        """Servo torque limit (Nm): the current limit, never above stall torque."""
        limit = self.stall_torque_Nm if self.torque_limit_Nm is None else self.torque_limit_Nm
        return min(limit, self.stall_torque_Nm)

    @property
    def lower_leg_mass_kg(self) -> float:
        return self.lower_leg_mass_fraction * self.mass_kg

    @property
    def link_inertia_kg_m2(self) -> float:
        """Lower leg about the knee: point mass at the centre of mass plus 10 % for its extent."""
        lc = self.lower_leg_com_fraction * self.lower_leg_m
        return 1.1 * self.lower_leg_mass_kg * lc * lc

    @property
    def gravity_amplitude_Nm(self) -> float:
        return self.lower_leg_mass_kg * G_M_PER_S2 * self.lower_leg_com_fraction * self.lower_leg_m

    def as_dict(self) -> dict[str, Any]:
        return {**asdict(self), "torque_limit_used_Nm": self.torque_limit,
                "link_inertia_kg_m2": self.link_inertia_kg_m2, "gravity_amplitude_Nm": self.gravity_amplitude_Nm}


def knee_effects(cfg: KneeConfig, ground: bool = False) -> EffectChain:
    """The knee simulator's effect chain; on by default: backlash, spring, gravity, friction,
    ground contact (when `ground`), gear friction in the effort, sensor noise and 12-bit
    quantisation. Everything else is declared but off (among them a Hall step and the effort's lag);
    switch with `EffectChain.configure`.
    """
    return EffectChain([
        DeadBand("backlash", width_rad=cfg.backlash_rad),
        DeadBand("dead_band", enabled=False),
        spring_law(cfg.k_Nm_per_rad, cfg.torque_curve),
        StiffnessScale("stiffness_scale", enabled=False),
        CubicStiffening("cubic_stiffening", enabled=False),
        DahlHysteresis("hysteresis", enabled=False),
        Viscoelastic("viscoelastic", enabled=False),
        ThermalSoftening("thermal_softening", enabled=False),
        GravityLoad("gravity", amplitude_Nm=cfg.gravity_amplitude_Nm, angle_offset_rad=-cfg.hip_flexion_rad),
        Friction("friction", coulomb_Nm=0.03, viscous_Nm_s_per_rad=0.15),
        StanceLoad("ground_contact", enabled=ground, weight_N=cfg.stance_weight_share * cfg.mass_kg * G_M_PER_S2,
                   upper_leg_m=cfg.upper_leg_m, lower_leg_m=cfg.lower_leg_m),
        SensorDelay("hall_delay", enabled=False),
        SensorOffset("hall_offset", enabled=False),
        SensorStep("hall_step", enabled=False),
        SensorDrift("hall_drift", enabled=False),
        SensorNoise("hall_noise", std_rad=0.002),
        Quantisation("hall_quantisation", bits=12),
        AngleWrap("hall_wrap", enabled=False),
        Quantisation("motor_quantisation", bind={"hall": "motor"}, bits=12),
        Friction("gear_friction", bind={"velocity": "motor_velocity", "load_torque": "effort"},
                 coulomb_Nm=GEAR_COULOMB_NM, viscous_Nm_s_per_rad=0.0),
        EffortLag("effort_lag", enabled=False),
        SensorNoise("effort_noise", bind={"hall": "effort"}, std_rad=0.05),
    ])


def bench_effects(k_Nm_per_rad: float, curve: TorqueCurve | None = None) -> EffectChain:
    """The bench simulator's chain: spring on (`curve` when given, else k); dead-band, torque-path effects,
    friction, sensor effects declared and off except torque and deflection noise; the torque channel's delay and
    low-pass (a filtered load-cell amplifier) off."""
    return EffectChain([
        DeadBand("dead_band", enabled=False),
        spring_law(k_Nm_per_rad, curve),
        StiffnessScale("stiffness_scale", enabled=False),
        CubicStiffening("cubic_stiffening", enabled=False),
        DahlHysteresis("hysteresis", enabled=False),
        Viscoelastic("viscoelastic", enabled=False),
        ThermalSoftening("thermal_softening", enabled=False),
        Friction("friction", enabled=False, bind={"velocity": "deflection_rate", "load_torque": "torque"}),
        SensorDelay("hall_delay", enabled=False),
        SensorOffset("hall_offset", enabled=False),
        SensorStep("hall_step", enabled=False),
        SensorDrift("hall_drift", enabled=False),
        SensorNoise("hall_noise", std_rad=0.001),
        Quantisation("hall_quantisation", enabled=False, bits=12),
        SensorDelay("torque_delay", enabled=False, bind={"hall": "torque_sensor"}),
        EffortLag("torque_lag", enabled=False, bind={"effort": "torque_sensor"}),
        SensorNoise("torque_noise", bind={"hall": "torque_sensor"}, std_rad=0.02),
    ])


def parse_effect_option(text: str) -> tuple[str, bool, dict[str, float]]:
    """'NAME', 'NAME:param=value,param=value' or 'NAME=off' -> (name, enabled, values)."""
    name, _, rest = text.partition(":")
    if name.endswith("=off") or name.endswith("=on"):
        name, _, state = name.partition("=")
        return name, state == "on", {}
    values = {}
    for item in filter(None, rest.split(",")):
        key, eq, val = item.partition("=")
        try:
            values[key.strip()] = float(val)
        except ValueError:
            raise ConfigError(f"effect option '{text}': '{item}' must be param=number") from None
        if not eq:
            raise ConfigError(f"effect option '{text}': '{item}' must be param=number")
    return name.strip(), True, values


def configure_chain(chain: EffectChain, options: list[str]) -> EffectChain:
    """Apply `parse_effect_option` strings to a chain in order."""
    for text in options:
        name, enabled, values = parse_effect_option(text)
        chain = chain.configure(name, enabled=enabled, **values)
    return chain


__all__ = ["KneeConfig", "bench_effects", "configure_chain", "knee_effects", "parse_effect_option"]
