"""The design space: which geometry keys are design axes, their values, and candidate names.

Any numeric key of `[geometry]` (dotted for nested tables, e.g. `hub_bolts.count`) can be an
axis under `[design_space]`; every other key is fixed under `[geometry]`. Candidates are the
full factorial of the axes, the first axis varying fastest (the thesis's order for beam count x
beam thickness).
"""

from __future__ import annotations

import itertools
import re
from dataclasses import dataclass

from seadesign.design.tomlcheck import Table

Value = int | float

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
    """One design axis: a dotted geometry key and the values it takes."""

    key: str
    values: tuple[Value, ...]


def label(key: str, value: Value) -> str:
    """How `key = value` reads in a candidate's name (e.g. "4 beams", "thickness 8 mm")."""
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
        if key not in AXIS_KEYS:
            raise space.error(space.key(key), "is not a numeric geometry key that can be a design axis; axes are "
                                              + ", ".join(sorted(AXIS_KEYS)))
        if lookup(fixed, key) is not None:
            raise space.error(space.key(key), f"is also fixed as geometry.{key}; a key is either a design axis "
                                              "or a fixed value: remove one of them")
        values = space.number_list(key, integer=key in INTEGER_KEYS)
        axes.append(Axis(key, values))
    space.done()
    return tuple(axes)


def grid(axes: tuple[Axis, ...]) -> list[tuple[tuple[str, Value], ...]]:
    """Every combination of axis values, the first axis varying fastest."""
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
        *parents, leaf = key.split(".")
        node = out
        for part in parents:
            node = node.setdefault(part, {})
        node[leaf] = value
    return out
