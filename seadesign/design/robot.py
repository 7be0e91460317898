"""The robot a spring serves, as a study file gives it: its body (the standing load), its servo, and the two load
cases (stall and impact torque), all SI; derived quantities such as the impact torque are computed here from
physical inputs, never typed in."""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass

from seadesign.constants import G_M_PER_S2
from seadesign.design.tomlcheck import Table


@dataclass(frozen=True)
class LoadCases:
    """The two load cases as physical inputs (SI)."""

    stall_torque_Nm: float  # servo stall torque, applied on the hub
    foot_cell_force_N: float  # largest single load-cell reading at impact
    foot_cell_count: int  # cells per foot; the thesis took max cell x count
    lower_leg_m: float  # knee to foot lever: the robot's lower leg (study key robot.lower_leg_m)
    impact_knee_angle_deg: float  # angle between force and lever at impact

    @property
    def foot_force_N(self) -> float:
        return self.foot_cell_force_N * self.foot_cell_count

    @property
    def impact_torque_Nm(self) -> float:
        """tau = r F sin(theta) (thesis eq. 5.1), applied on the backplate side."""
        return self.lower_leg_m * self.foot_force_N * math.sin(math.radians(self.impact_knee_angle_deg))


@dataclass(frozen=True)
class Robot:
    """Robot data for the standing load and the simulator (SI)."""

    mass_kg: float
    upper_leg_m: float
    lower_leg_m: float
    standing_knee_flexion_deg: float  # knee bend when standing

    @property
    def standing_knee_torque_Nm(self) -> float:
        """Static knee torque standing on two legs: half the weight acting on the lower leg's
        horizontal lever, lower_leg sin(flexion / 2) (hip above ankle, both segments tilted
        by half the flexion)."""
        return self.mass_kg * G_M_PER_S2 / 2 * self.lower_leg_m * math.sin(math.radians(self.standing_knee_flexion_deg) / 2)


@dataclass(frozen=True)
class Actuator:
    """Servo data (the stall torque lives in the load cases)."""

    gear_ratio: float
    no_load_speed_rpm: float
    backlash_deg: float


def _impact_lever(lc: Table, robot: Robot) -> float:
    """The impact lever is the robot's lower leg. Older study files also gave it as
    load_cases.lower_leg_m: still read, with a deprecation message, and refused when it differs."""
    old = lc.number("lower_leg_m", required=False, gt=0)
    if old is not None:
        if old != robot.lower_leg_m:
            raise lc.error(lc.key("lower_leg_m"), f"({old:g} m) differs from robot.lower_leg_m ({robot.lower_leg_m:g} m); "
                                                  "the impact lever is the lower leg: remove load_cases.lower_leg_m")
        warnings.warn(f"{lc.file}: load_cases.lower_leg_m is deprecated (it repeats robot.lower_leg_m, which the "
                      "impact torque now uses); remove it from the study file", FutureWarning, stacklevel=3)
    return robot.lower_leg_m


def read_robot(top: Table) -> Robot:
    """[robot] of a study file."""
    r = top.table("robot")
    robot = Robot(r.number("mass_kg", gt=0), r.number("upper_leg_m", gt=0), r.number("lower_leg_m", gt=0),
                  r.number("standing_knee_flexion_deg", ge=0, lt=180))
    r.done()
    return robot


def read_load_cases(top: Table, robot: Robot) -> LoadCases:
    """[load_cases] of a study file; the impact lever is the robot's lower leg."""
    lc = top.table("load_cases")
    load_cases = LoadCases(
        stall_torque_Nm=lc.number("stall_torque_Nm", gt=0),
        foot_cell_force_N=lc.number("foot_cell_force_N", gt=0),
        foot_cell_count=lc.integer("foot_cell_count", ge=1),
        lower_leg_m=_impact_lever(lc, robot),
        impact_knee_angle_deg=lc.number("impact_knee_angle_deg", gt=0, lt=180),
    )
    lc.done()
    return load_cases


def read_actuator(top: Table) -> Actuator:
    """[actuator] of a study file."""
    a = top.table("actuator")
    actuator = Actuator(a.number("gear_ratio", gt=0), a.number("no_load_speed_rpm", gt=0), a.number("backlash_deg", ge=0))
    a.done()
    return actuator
