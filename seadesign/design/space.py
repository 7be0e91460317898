"""The design space: which geometry keys are design axes, their values, and candidate names.

Any numeric key of `[geometry]` (dotted for nested tables, e.g. `hub_bolts.count`), and
`material` (a list of material files), can be an axis under `[design_space]`; every other key is
fixed under `[geometry]`. An axis is a list of values (`[3, 4, 5]`), a range with a step
(`{min = 3, max = 10, step = 1}`, both ends included) or continuous bounds
(`{min = 6.0, max = 20.0}`). The grid of a sweep is the full factorial of the discrete axes, the
first axis varying fastest (the thesis's order for beam count x beam thickness); continuous axes
are for the explorer. Continuous values are kept exact (cache keys, tables, spring.json) and
rounded to 0.01 of their unit in candidate names.
"""

from __future__ import annotations

import itertools
import math
import re
from dataclasses import dataclass

from seadesign.design.tomlcheck import Table
from seadesign.errors import ConfigError

Value = int | float | str
MATERIAL_KEY = "material"
NAME_DECIMALS = 2  # continuous values are rounded to 0.01 of their unit (mm, deg) in names

# How a value of a key reads in a candidate's name; other keys read "<key without unit> <value> <unit>".
LABELS = {"beam_count": "{:d} beams", "beam_thickness_mm": "{:g} mm"}
UNITS = {"_mm": "mm", "_deg": "deg"}
INTEGER_KEYS = frozenset({"beam_count", "hub_bolts.count", "ring_bolts.count"})
AXIS_KEYS = frozenset({
    "beam_count", "beam_thickness_mm", "hub_radius_mm", "arc_radius_mm", "ring_width_mm", "thickness_mm",
    "first_beam_angle_deg", "fillet_radius_mm", "bore_radius_mm",
    *(f"{side}_bolts.{k}" for side in ("hub", "ring") for k in (
        "count", "circle_diameter_mm", "hole_diameter_mm", "start_angle_deg", "counterbore_diameter_mm",
        "counterbore_depth_mm")),
    "nut_slots.width_mm", "nut_slots.z_min_mm", "nut_slots.z_max_mm",
})


@dataclass(frozen=True)
class Axis:
    """One design axis: a dotted geometry key (or `material`) and the values it takes, or for a
    continuous axis its bounds (in the key's unit)."""

    key: str
    values: tuple[Value, ...] = ()
    bounds: tuple[float, float] | None = None

    @property
    def continuous(self) -> bool:
        return self.bounds is not None

    def contains(self, value: Value) -> bool:
        if self.bounds is not None:
            return isinstance(value, (int, float)) and self.bounds[0] <= value <= self.bounds[1]
        return value in self.values

    def exact(self, value: Value) -> Value:
        """`value` in the axis's own type (the listed value it equals, or a float in bounds)."""
        return float(value) if self.bounds is not None else self.values[self.values.index(value)]

    def describe(self) -> str:
        if self.bounds is not None:
            return f"{self.key} in [{self.bounds[0]:g}, {self.bounds[1]:g}]"
        return f"{self.key} in {list(self.values)}"


def label(key: str, value: Value) -> str:
    """How `key = value` reads in a candidate's name (e.g. "4 beams", "thickness 8 mm"); floats
    are rounded to NAME_DECIMALS."""
    if isinstance(value, str):
        return value
    if isinstance(value, float):
        value = round(value, NAME_DECIMALS) + 0.0  # + 0.0: no "-0"
    if key in LABELS:
        return LABELS[key].format(value)
    words = key.replace("_", " ").replace(".", " ")
    for suffix, unit in UNITS.items():
        if key.endswith(suffix):
            return f"{words[: -len(suffix)]} {value:g} {unit}"
    return f"{words} {value:g}"


def axis_label(key: str) -> str:
    """A plot-axis label with the unit, e.g. "beam count (-)", "thickness (mm)"."""
    words = key.replace("_", " ").replace(".", " ")
    for suffix, unit in UNITS.items():
        if key.endswith(suffix):
            return f"{words[: -len(suffix)]} ({unit})"
    return f"{words} (-)"


def candidate_name(values: tuple[tuple[str, Value], ...]) -> str:
    """The name of the candidate with these axis values ("4 beams x 8 mm")."""
    return " x ".join(label(k, v) for k, v in values) or "the fixed design"


def file_stem(name: str) -> str:
    """A file-name-safe stem of a candidate name ("4 beams x 8 mm" -> "4beams_8mm")."""
    return re.sub(r"[^A-Za-z0-9_.-]", "", name.replace(" x ", "_"))


def read_axes(space: Table, fixed: dict) -> tuple[Axis, ...]:
    """The axes of a `[design_space]` table; `fixed` is the raw `[geometry]` table (a key may be
    an axis or fixed, not both)."""
    axes = []
    for key in list(space.data):
        if key == MATERIAL_KEY:
            axes.append(Axis(key, space.string_list(key)))
            continue
        if key not in AXIS_KEYS:
            raise space.error(space.key(key), "is not a numeric geometry key that can be a design axis; axes are "
                                              + ", ".join(sorted(AXIS_KEYS | {MATERIAL_KEY})))
        if lookup(fixed, key) is not None:
            raise space.error(space.key(key), f"is also fixed as geometry.{key}; a key is either a design axis "
                                              "or a fixed value: remove one of them")
        axes.append(_numeric_axis(space, key))
    space.done()
    return tuple(axes)


def _numeric_axis(space: Table, key: str) -> Axis:
    """A list, a {min, max, step} range (both ends included) or {min, max} bounds."""
    integer = key in INTEGER_KEYS
    if not isinstance(space.data[key], dict):
        return Axis(key, space.number_list(key, integer=integer))
    spec = space.table(key)
    lo, hi = spec.number("min"), spec.number("max")
    step = spec.number("step", required=False, gt=0)
    spec.done()
    if not lo < hi:
        raise spec.error(spec.key("max"), f"must be larger than min ({hi:g} <= {lo:g})")
    if step is None:
        if integer:
            raise spec.error(spec.key("step"), "is needed: an integer key cannot be continuous; give step = 1")
        return Axis(key, bounds=(lo, hi))
    n = math.floor((hi - lo) / step + 1e-9)
    values = [lo + i * step for i in range(n + 1)]
    if integer:
        if not all(float(v).is_integer() for v in (lo, step)):
            raise spec.error(spec.key("step"), "min and step of an integer key must be integers")
        values = [int(round(v)) for v in values]
    else:
        values = [round(v, 12) for v in values]  # 0.1 steps without binary noise
    return Axis(key, tuple(values))


def grid(axes: tuple[Axis, ...]) -> list[tuple[tuple[str, Value], ...]]:
    """Every combination of axis values, the first axis varying fastest (discrete axes only)."""
    continuous = [a.key for a in axes if a.continuous]
    if continuous:
        raise ConfigError(f"the continuous axes {continuous} have no grid; explore them (`seadesign explore`), or give "
                          "each of them values or a step in [design_space]")
    combos = itertools.product(*(a.values for a in reversed(axes)))
    return [tuple(zip((a.key for a in axes), reversed(c))) for c in combos]


def lookup(table: dict, key: str):
    """The value at a dotted key of a nested dict, None when absent."""
    for part in key.split("."):
        if not isinstance(table, dict) or part not in table:
            return None
        table = table[part]
    return table


def merged(fixed: dict, values: tuple[tuple[str, Value], ...]) -> dict:
    """A copy of the nested geometry table with the axis values set at their dotted keys."""
    out = {k: dict(v) if isinstance(v, dict) else v for k, v in fixed.items()}
    for key, value in values:
        if key == MATERIAL_KEY:
            continue
        *parents, leaf = key.split(".")
        node = out
        for part in parents:
            node = node.setdefault(part, {})
        node[leaf] = value
    return out
