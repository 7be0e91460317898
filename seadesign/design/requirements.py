"""What a spring must do, in physical terms, and what is minimised among the springs that do.

Read from a study's `[ranking]` (the standing sag limit and an optional k range, as before) and an
optional `[requirements]` table:

    [requirements]
    k_Nm_per_rad = { min = 20.0, max = 200.0 }          # or { target = 40.0, tolerance_percent = 10.0 }
    loads = ["stall", "impact"]    # carried without contact or another stop, within the allowable strain
    max_outer_diameter_mm = 80.0   # envelope
    max_thickness_mm = 20.0
    objectives = ["mass", "accuracy", "protection"]     # minimised; the first decides among feasible designs

How each is judged on solved designs (from the large-deflection path, never from the linear model
except k, which is the small-load stiffness by definition) is `sweep/requirements.py`; the
printability rules are `[validity]`.
"""

from __future__ import annotations

from dataclasses import dataclass

from seadesign.design.tomlcheck import Table

LOADS = ("stall", "impact")  # the load cases a path is read at that a requirement can name
OBJECTIVES = ("mass", "accuracy", "protection")


@dataclass(frozen=True)
class Requirements:
    """A study's requirements (None: not required) and objectives."""

    max_standing_deflection_deg: float  # knee sag under the standing load, read from the curve
    k_min_Nm_per_rad: float | None = None  # small-load stiffness range
    k_max_Nm_per_rad: float | None = None
    loads: tuple[str, ...] = LOADS  # carried without contact or another stop, peak strain within the allowable
    max_outer_diameter_mm: float | None = None
    max_thickness_mm: float | None = None
    objectives: tuple[str, ...] = OBJECTIVES


def _k_range(rk: Table, req: Table | None) -> tuple[float | None, float | None]:
    """The k range from [ranking] (k_min / k_max) or [requirements] (k_Nm_per_rad), not both."""
    old = rk.number("k_min_Nm_per_rad", gt=0, required=False), rk.number("k_max_Nm_per_rad", gt=0, required=False)
    if req is None or req.raw("k_Nm_per_rad") is None:
        return old
    if any(v is not None for v in old):
        raise req.error(req.key("k_Nm_per_rad"), "is also given as ranking.k_min_Nm_per_rad / k_max_Nm_per_rad; "
                                                 "give the k range once: remove one of them")
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


def read_requirements(rk: Table, req: Table | None) -> Requirements:
    """The requirements of a study from its [ranking] table (read, not closed) and [requirements] (closed)."""
    k_min, k_max = _k_range(rk, req)
    standing = rk.number("max_standing_deflection_deg", gt=0)
    if req is None:
        return Requirements(standing, k_min, k_max)
    out = Requirements(
        standing, k_min, k_max,
        loads=_names(req, "loads", LOADS, LOADS),
        max_outer_diameter_mm=req.number("max_outer_diameter_mm", gt=0, required=False),
        max_thickness_mm=req.number("max_thickness_mm", gt=0, required=False),
        objectives=_names(req, "objectives", OBJECTIVES, OBJECTIVES),
    )
    req.done()
    return out
