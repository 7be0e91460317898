"""Loads on the link: torque the link needs from the spring beyond its inertia.

Convention: J angle'' = spring torque - load_torque, knee flexion positive. Each effect adds
its share to `load_torque`; bound to other signals (e.g. `effort`, `motor_velocity`) the same
objects model gearbox friction or a bench's friction.
"""

from __future__ import annotations

import numpy as np

from seadesign.constants import G_M_PER_S2, WOLFGANG_LOWER_LEG_M, WOLFGANG_MASS_KG
from seadesign.effects.base import EXACT, Effect, Param, Scales, Search


class Friction(Effect):
    """Coulomb + viscous friction: load += Fc tanh(v / vs) + Fv v (tanh: a smooth sign)."""

    key = "friction"
    summary = "load += Fc tanh(v/vs) + Fv v"
    parameters = (
        Param("coulomb_Nm", "Nm", 0.05, 0.0, 20.0, "Coulomb friction torque Fc"),
        Param("viscous_Nm_s_per_rad", "Nm s/rad", 0.02, 0.0, 50.0, "viscous coefficient Fv"),
        Param("smoothing_rad_per_s", "rad/s", 0.05, 1e-5, 10.0, "velocity vs below which the Coulomb term fades"),
    )
    signature = "jump at v = 0 and slope vs v"
    reads = ("velocity",)
    writes = "load_torque"
    log_params = ("smoothing_rad_per_s",)

    def _map(self, x, p, rng, xp=np, options=EXACT):
        v = x["velocity"]
        return x["load_torque"] + p["coulomb_Nm"] * xp.tanh(v / p["smoothing_rad_per_s"]) + p["viscous_Nm_s_per_rad"] * v

    def search(self, s: Scales) -> Search:
        span, v = s.torque_Nm, s.velocity_rad_per_s
        low = -1.0 if s.generic else 0.0  # friction opposes motion; a generic table's sign is its own
        return ({"coulomb_Nm": (low * span, span), "viscous_Nm_s_per_rad": (low * 100 * span / v, 100 * span / v),
                 "smoothing_rad_per_s": (1e-4 * v, v)},
                [{"coulomb_Nm": 0.01 * span, "viscous_Nm_s_per_rad": 0.0, "smoothing_rad_per_s": f * v} for f in (0.02, 0.2)])


class GravityLoad(Effect):
    """Gravity on the hanging lower leg: load += A sin(angle + phi), A = m g l_c."""

    key = "gravity"
    summary = "load += A sin(angle + phi)"
    parameters = (
        Param("amplitude_Nm", "Nm", 0.6, 0.0, 100.0, "m g l_c of the lower leg and foot"),
        Param("angle_offset_rad", "rad", 0.0, -np.pi, np.pi, "angle phi at which the leg hangs straight down, negated"),
    )
    signature = "follows the link angle, present at v = 0"
    reads = ("angle",)
    writes = "load_torque"

    def _map(self, x, p, rng, xp=np, options=EXACT):
        return x["load_torque"] + p["amplitude_Nm"] * xp.sin(x["angle"] + p["angle_offset_rad"])

    def search(self, s: Scales) -> Search:
        return ({"amplitude_Nm": (0.0, min(100.0, 2 * s.torque_Nm)), "angle_offset_rad": (-np.pi, np.pi)},
                [{"amplitude_Nm": 0.1 * s.torque_Nm, "angle_offset_rad": phi} for phi in (-2.0, 0.0, 2.0)])


class StanceLoad(Effect):
    """Body weight on a bent leg in stance: load -= W l2 sin(a2), hip above ankle.

    With thigh l1 and shank l2 and knee angle q, the shank leans a2 from vertical with
    tan a2 = l1 sin q / (l2 + l1 cos q); the weight share W (N) then flexes the knee with
    W l2 sin a2, scaled by the leg's share `stance` of the weight (0 in swing).
    """

    key = "ground_contact"
    summary = "stance: load -= W l2 sin(a2(angle)), weight W on a hip-over-ankle leg"
    parameters = (
        Param("weight_N", "N", 0.5 * WOLFGANG_MASS_KG * G_M_PER_S2, 0.0, 2000.0, "supported body weight W (on both legs together)"),
        Param("upper_leg_m", "m", 0.2, 0.01, 2.0, "thigh length l1"),
        Param("lower_leg_m", "m", WOLFGANG_LOWER_LEG_M, 0.01, 2.0, "shank length l2"),
    )
    reads = ("angle", "stance")
    writes = "load_torque"

    def _map(self, x, p, rng, xp=np, options=EXACT):
        q = x["angle"]
        l1, l2 = p["upper_leg_m"], p["lower_leg_m"]
        lean = xp.atan2(l1 * xp.sin(q), l2 + l1 * xp.cos(q))
        return x["load_torque"] - x["stance"] * p["weight_N"] * l2 * xp.sin(lean)
