"""The physical columns a ranking reads, from the large-deflection path (`large_` columns): the standing
deflection, the foot error at stall, the gearbox strike, the working range, the usable torque, the share of the
strain limits used and the thesis's numbers.

Protection: the leg (inertia J about the knee, angular speed w = v / lower_leg at touchdown) is
stopped by the spring with the gearbox side held: its kinetic energy J w^2 / 2 goes into the
spring, int_0^theta T dtheta, and the torque where the curve has stored it is the peak. (A linear
spring gives tau_peak = w sqrt(k J).) A curve that ends before it has stored that energy gives
no number: the strike reaches the path's stop. A static reaction force cannot measure protection:
in statics the whole applied torque reaches the motor whatever k is (the thesis's 149-150 N for
every design).
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from seadesign.constants import THESIS_FEA_RESULTS
from seadesign.design.spring import TorqueCurve
from seadesign.design.study import Study
from seadesign.sweep.handoff import curve_to_stop
from seadesign.sweep.requirements import PROTECTION, STRAIN_USE, USABLE, limit_torque, strain_use, working_range


def physical_columns(table: pd.DataFrame, study: Study) -> pd.DataFrame:
    """Standing deflection, foot error at stall, impact energy, gearbox strike torque and the energy the curve
    stores to its stop, the working range's tangents, natural frequency and torque per sensor count, the
    usable torque (the smaller of where the path stops and where the tensile strain passes the cyclic limit),
    the share of the strain limits used, thesis numbers."""
    rk, robot = study.ranking, study.robot
    t = table.copy()
    energy = 0.5 * rk.knee_inertia_kg_m2 * study.strike_speed_rad_per_s ** 2
    solved = t["status"] == "ok"
    t["standing_knee_torque_Nm"] = robot.standing_knee_torque_Nm
    t["standing_deflection_deg"] = np.degrees(t["large_standing_rotation_rad"]) if "large_standing_rotation_rad" in t \
        else np.nan
    t["stall_foot_error_mm"] = t["large_stall_rotation_rad"] * robot.lower_leg_m * 1e3 if "large_stall_rotation_rad" \
        in t else np.nan
    t["strike_energy_J"] = energy
    if "large_stop_torque_Nm" in t:
        t[USABLE] = pd.concat([t["large_stop_torque_Nm"], limit_torque(t, "cyclic")], axis=1).min(axis=1, skipna=True)
    curves = [TorqueCurve(*map(tuple, curve_to_stop(r))) if ok else None for ok, (_, r) in zip(solved, t.iterrows())]
    t["large_stop_energy_J"] = [np.nan if c is None else c.energy_J for c in curves]
    t[PROTECTION] = np.array([None if c is None else c.torque_at_energy(energy) for c in curves], dtype=float)
    t = pd.concat([t.drop(columns=[c for c in ("working_min_tangent_k_Nm_per_rad", "working_max_tangent_k_Nm_per_rad",
                                               "natural_frequency_Hz", "torque_per_count_Nm") if c in t]),
                   working_range(t, study)], axis=1)
    t[STRAIN_USE] = strain_use(t, study)
    thesis = [_thesis_result(study, row) for _, row in t.iterrows()]
    t["thesis_reaction_N"] = [r for r, _ in thesis]
    t["thesis_displacement_mm"] = [d for _, d in thesis]
    return t


def _thesis_result(study: Study, row: pd.Series) -> tuple[float, float]:
    """The thesis's (reaction N, displacement mm) for the row's beam count and thickness, when it reports them."""
    p = study.candidate_of_row(row).params
    return THESIS_FEA_RESULTS.get((p.beam_count, p.beam_thickness_mm), (math.nan, math.nan))
