"""What a spring must do for the robot, in the units a designer thinks in, and what decides among the springs
that do it.

Read from a study's `[requirements]` table; every key is optional and carries its unit in its name:

    [requirements]
    max_standing_deflection_deg = 10.0   # knee sag under the standing load, read from the curve
    max_stall_foot_error_mm = 40.0       # foot displacement (lower leg x rotation) at the stall torque
    max_torque_per_count_Nm = 0.1        # torque one count of the deflection sensor stands for (working range)
    min_natural_frequency_Hz = 4.0       # lower leg on the spring (knee inertia), over the working range
    max_strike_torque_Nm = 8.0           # torque a foot strike drives into the gearbox, read from the curve
    k_Nm_per_rad = { min = 20.0, max = 200.0 }   # or { target = 40.0, tolerance_percent = 10.0 }: small-load k
    loads = ["stall", "impact"]          # carried without a stop, tensile strain within the load class's limit
    max_outer_diameter_mm = 80.0         # envelope
    max_thickness_mm = 20.0
    objectives = ["softest_k", "mass"]   # minimised; the first decides among feasible designs, mass breaks ties

The working range is rest to the stall torque: its tangent stiffness is bounded from above by the sensor's
resolution (one count of 2 pi / 2^12 rad, the AS5600) and from below by the natural frequency. Together with
the sag, the foot error, the strike torque and an explicit k range they imply a k window (`k_window`); bounds
that cross on the study's own numbers are refused before any solve. How each requirement is judged on a
solved design is `sweep/requirements.py`; the printability rules are `[validity]`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from seadesign.constants import AS5600_BITS
from seadesign.design.tomlcheck import Table
from seadesign.errors import ConfigError

LOADS = ("stall", "impact")  # the load cases a path is read at that a requirement can name
OBJECTIVES = ("mass", "accuracy", "protection", "strain_margin", "softest_k")
RAD_PER_COUNT = 2.0 * math.pi / 2**AS5600_BITS  # the deflection sensor's resolution (rad)
# keys that moved from [ranking] to [requirements], and what replaces the weighted score's weights
MOVED = {"max_standing_deflection_deg": "requirements.max_standing_deflection_deg",
         "k_min_Nm_per_rad": "requirements.k_Nm_per_rad = { min = ... }",
         "k_max_Nm_per_rad": "requirements.k_Nm_per_rad = { max = ... }",
         "weight_accuracy": "requirements.objectives (the first decides; e.g. [\"accuracy\", \"mass\"])",
         "weight_protection": "requirements.objectives (the first decides; e.g. [\"protection\", \"mass\"])"}


@dataclass(frozen=True)
class Requirements:
    """A study's requirements (None: not required) and objectives."""

    max_standing_deflection_deg: float | None = None
    max_stall_foot_error_mm: float | None = None
    max_torque_per_count_Nm: float | None = None
    min_natural_frequency_Hz: float | None = None
    max_strike_torque_Nm: float | None = None
    k_min_Nm_per_rad: float | None = None  # small-load stiffness range
    k_max_Nm_per_rad: float | None = None
    loads: tuple[str, ...] = LOADS
    max_outer_diameter_mm: float | None = None
    max_thickness_mm: float | None = None
    objectives: tuple[str, ...] = ("mass",)


@dataclass(frozen=True)
class KBound:
    """One bound a requirement puts on the spring's stiffness (Nm/rad), from the study's own numbers."""

    key: str  # the requirement's key
    stiffness_Nm_per_rad: float
    lower: bool  # a lower bound (else an upper one)
    measure: str  # which stiffness it bounds, in words
    reason: str  # why, in words


@dataclass(frozen=True)
class KWindow:
    """The stiffness window the requirements imply: their bounds, and the binding lower and upper one."""

    bounds: tuple[KBound, ...]

    @property
    def lower(self) -> KBound | None:
        lows = [b for b in self.bounds if b.lower]
        return max(lows, key=lambda b: b.stiffness_Nm_per_rad) if lows else None

    @property
    def upper(self) -> KBound | None:
        highs = [b for b in self.bounds if not b.lower]
        return min(highs, key=lambda b: b.stiffness_Nm_per_rad) if highs else None

    def describe(self) -> str:
        """"k between A and B Nm/rad: A from ..., B from ..." in words."""
        lo, hi = self.lower, self.upper
        if lo is None and hi is None:
            return "The requirements put no bound on the stiffness."
        parts = [f"{b.stiffness_Nm_per_rad:.3g} Nm/rad from {b.reason} ({b.measure})" for b in (lo, hi) if b]
        if lo and hi:
            return f"k between {lo.stiffness_Nm_per_rad:.3g} and {hi.stiffness_Nm_per_rad:.3g} Nm/rad: " + "; ".join(parts)
        return ("k at least " if lo else "k at most ") + parts[0]


def k_window(req: Requirements, *, standing_torque_Nm: float, stall_torque_Nm: float, lower_leg_m: float,
             knee_inertia_kg_m2: float, strike_speed_rad_per_s: float) -> KWindow:
    """The stiffness bounds each requirement implies for a linear spring (a curve is judged on itself later):
    sag theta <= limit at the standing torque, foot error l theta <= limit at the stall torque, natural frequency
    sqrt(k / J) / 2 pi >= limit, one sensor count k q <= limit, a strike's peak torque w sqrt(k J) <= limit
    (the leg's kinetic energy J w^2 / 2 stored in the spring), and the explicit k range."""
    b = []
    if req.max_standing_deflection_deg is not None:
        b.append(KBound("max_standing_deflection_deg", standing_torque_Nm / math.radians(req.max_standing_deflection_deg),
                        True, "secant at the standing torque", "the standing sag"))
    if req.max_stall_foot_error_mm is not None:
        b.append(KBound("max_stall_foot_error_mm", stall_torque_Nm * lower_leg_m / (req.max_stall_foot_error_mm * 1e-3),
                        True, "secant at the stall torque", "the foot error at stall"))
    if req.min_natural_frequency_Hz is not None:
        b.append(KBound("min_natural_frequency_Hz", knee_inertia_kg_m2 * (2 * math.pi * req.min_natural_frequency_Hz) ** 2,
                        True, "tangent over the working range", "the bandwidth"))
    if req.k_min_Nm_per_rad is not None:
        b.append(KBound("k_Nm_per_rad.min", req.k_min_Nm_per_rad, True, "small-load k", "the explicit k range"))
    if req.max_torque_per_count_Nm is not None:
        b.append(KBound("max_torque_per_count_Nm", req.max_torque_per_count_Nm / RAD_PER_COUNT, False,
                        "tangent over the working range", "the sensor resolution"))
    if req.max_strike_torque_Nm is not None:
        b.append(KBound("max_strike_torque_Nm", (req.max_strike_torque_Nm / strike_speed_rad_per_s) ** 2
                        / knee_inertia_kg_m2, False, "linear-spring estimate", "the gearbox protection"))
    if req.k_max_Nm_per_rad is not None:
        b.append(KBound("k_Nm_per_rad.max", req.k_max_Nm_per_rad, False, "small-load k", "the explicit k range"))
    return KWindow(tuple(b))


def check_window(window: KWindow, file: str) -> None:
    """Refuse bounds that cross on the study's own numbers, naming both requirements and by how much."""
    lo, hi = window.lower, window.upper
    if lo is not None and hi is not None and lo.stiffness_Nm_per_rad > hi.stiffness_Nm_per_rad:
        raise ConfigError(
            f"{file}: requirements.{lo.key} needs k >= {lo.stiffness_Nm_per_rad:.4g} Nm/rad ({lo.reason}, "
            f"{lo.measure}), but requirements.{hi.key} allows k <= {hi.stiffness_Nm_per_rad:.4g} Nm/rad ({hi.reason}, "
            f"{hi.measure}): they cross by {100 * (lo.stiffness_Nm_per_rad / hi.stiffness_Nm_per_rad - 1):.3g} %, so "
            "no spring can meet both; relax one of them")


def _k_range(req: Table) -> tuple[float | None, float | None]:
    """The explicit small-load k range (`k_Nm_per_rad`): min and/or max, or target and tolerance."""
    if req.raw("k_Nm_per_rad") is None:
        return None, None
    k = req.table("k_Nm_per_rad")
    if k.raw("target") is not None:
        target, tol = k.number("target", gt=0), k.number("tolerance_percent", gt=0, lt=100)
        k.done()
        return target * (1 - tol / 100), target * (1 + tol / 100)
    lo, hi = k.number("min", gt=0, required=False), k.number("max", gt=0, required=False)
    k.done()
    if lo is None and hi is None:
        raise k.error(k.where, "needs min and/or max (Nm/rad), or target and tolerance_percent")
    if lo is not None and hi is not None and not lo < hi:
        raise k.error(k.key("max"), f"must be larger than min ({hi:g} <= {lo:g})")
    return lo, hi


def _names(req: Table, key: str, allowed: tuple[str, ...], default: tuple[str, ...]) -> tuple[str, ...]:
    if req.raw(key) is None:
        return default
    names = req.string_list(key)
    bad = [n for n in names if n not in allowed]
    if bad:
        raise req.error(req.key(key), f"has {bad[0]!r}; choose from {', '.join(allowed)}")
    return names


def refuse_moved_keys(rk: Table) -> None:
    """The [ranking] keys that moved to [requirements] (or were replaced) get an error naming the new key."""
    for old, new in MOVED.items():
        if rk.raw(old) is not None:
            raise rk.error(rk.key(old), f"has moved: write {new} instead, and remove this line")


def read_requirements(req: Table | None) -> Requirements:
    """The requirements of a study from its [requirements] table (closed; None: no requirement but the loads)."""
    if req is None:
        return Requirements()
    k_min, k_max = _k_range(req)

    def limit(key: str) -> float | None:
        return req.number(key, gt=0, required=False)

    out = Requirements(
        max_standing_deflection_deg=limit("max_standing_deflection_deg"),
        max_stall_foot_error_mm=limit("max_stall_foot_error_mm"),
        max_torque_per_count_Nm=limit("max_torque_per_count_Nm"),
        min_natural_frequency_Hz=limit("min_natural_frequency_Hz"),
        max_strike_torque_Nm=limit("max_strike_torque_Nm"),
        k_min_Nm_per_rad=k_min,
        k_max_Nm_per_rad=k_max,
        loads=_names(req, "loads", LOADS, LOADS),
        max_outer_diameter_mm=limit("max_outer_diameter_mm"),
        max_thickness_mm=limit("max_thickness_mm"),
        objectives=_names(req, "objectives", OBJECTIVES, ("mass",)),
    )
    req.done()
    return out
