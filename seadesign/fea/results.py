"""Typed FEA results, units in the field names, each quantity with its rule for the applied torque.

Every number is a dataclass field made by `linear()`, `inverse()` or `unscaled()`: how it changes
when the load case's torque T is multiplied by s (x s, / s, unchanged). Fields that hold another
results dataclass are scaled through their own fields. `scaled` applies the rules and refuses a
field without one; `columns` flattens a result into the results table's columns
(`stall.von_mises_max.MPa` -> `stall_von_mises_max_MPa`).
"""

from __future__ import annotations

import dataclasses
import enum
from dataclasses import dataclass, field, replace
from typing import Any


class Scaling(enum.Enum):
    LINEAR = "linear"  # proportional to the torque (magnitude: the torques are positive)
    INVERSE = "inverse"  # proportional to 1 / torque (a safety factor)
    NONE = "none"  # does not depend on the torque (stiffness, locations, mesh, timings)


def linear() -> Any:
    return field(metadata={"scaling": Scaling.LINEAR})


def inverse() -> Any:
    return field(metadata={"scaling": Scaling.INVERSE})


def unscaled() -> Any:
    return field(metadata={"scaling": Scaling.NONE})


def nested(prefix: str | None = None) -> Any:
    """A field holding a results dataclass; its columns are named `<prefix><inner name>`
    (default prefix: `<field name>_`)."""
    return field(metadata={"prefix": prefix})


@dataclass(frozen=True)
class StressPeak:
    """The peak of one stress measure over the nodes (MPa) and where it is (part frame, mm)."""

    MPa: float = linear()
    x_mm: float = unscaled()
    y_mm: float = unscaled()
    z_mm: float = unscaled()


@dataclass(frozen=True)
class PeakStresses:
    """The peak stresses of one load case, and the safety factor against yield they give."""

    von_mises_max: StressPeak = nested()
    principal_1_max: StressPeak = nested()
    principal_3_min: StressPeak = nested()
    max_shear_max: StressPeak = nested()
    safety_factor: float = inverse()  # yield strength / peak von Mises


@dataclass(frozen=True)
class StallResult:
    """Stall torque on the hub, ring held."""

    torque_Nm: float = linear()
    rotation_rad: float = linear()
    bearing_displacement_mm: float = linear()  # largest displacement on the bearing circle
    stresses: PeakStresses = nested("")


@dataclass(frozen=True)
class ImpactResult:
    """Impact torque on the ring (backplate side), hub held; reactions on the hub bolts."""

    torque_Nm: float = linear()
    reaction_per_bolt_N: float = linear()  # largest resultant force on one hub bolt's coupling
    reaction_per_bolt_min_N: float = linear()
    bolt_count: float = unscaled()
    peak_nodal_reaction_N: float = linear()  # largest single nodal force (mesh dependent)
    stresses: PeakStresses = nested("")


@dataclass(frozen=True)
class SolveStats:
    """How the solve was made: element order, sizes, mesh quality, timings (s)."""

    element_order: float = unscaled()
    dofs: float = unscaled()
    mesh_nodes: float = unscaled()
    mesh_tets: float = unscaled()
    mesh_min_dihedral_deg: float = unscaled()
    mesh_max_aspect_ratio: float = unscaled()
    time_setup_s: float = unscaled()
    time_assembly_s: float = unscaled()
    time_factorization_s: float = unscaled()
    time_solve_s: float = unscaled()
    time_stress_s: float = unscaled()


@dataclass(frozen=True)
class LinearResults:
    """Both load cases of the linear model from one factorization."""

    k_Nm_per_rad: float = unscaled()
    equilibrium_rel_error: float = unscaled()  # |reaction torque + applied torque| / applied torque
    stall: StallResult = nested()
    impact: ImpactResult = nested()
    stats: SolveStats = nested("")

    @property
    def safety_factor(self) -> float:
        """The smaller of the two load cases' safety factors (yield / peak von Mises)."""
        return min(self.stall.stresses.safety_factor, self.impact.stresses.safety_factor)

    def columns(self) -> dict[str, float]:
        """The results table's columns of this solve (see `columns`), with the overall safety factor."""
        return {**columns(self), "safety_factor": self.safety_factor}

    def at(self, stall_torque_Nm: float, impact_torque_Nm: float) -> "LinearResults":
        """The same solve at other (positive) load-case torques: each case scaled by its own ratio."""
        return replace(self, stall=scaled(self.stall, stall_torque_Nm / self.stall.torque_Nm),
                       impact=scaled(self.impact, impact_torque_Nm / self.impact.torque_Nm))


def scaled(result: Any, factor: float) -> Any:
    """`result` with every field changed by its rule for a torque `factor` (> 0) times larger."""
    if not factor > 0:
        raise ValueError(f"torque factor must be positive, got {factor}")
    changes = {}
    for f in dataclasses.fields(result):
        value = getattr(result, f.name)
        if dataclasses.is_dataclass(value):
            changes[f.name] = scaled(value, factor)
            continue
        rule = f.metadata.get("scaling")
        if rule is None:
            raise TypeError(f"{type(result).__name__}.{f.name} has no torque-scaling rule; declare it with "
                            "linear(), inverse() or unscaled()")
        changes[f.name] = value * factor if rule is Scaling.LINEAR else value / factor if rule is Scaling.INVERSE \
            else value
    return replace(result, **changes)


def columns(result: Any, prefix: str = "") -> dict[str, Any]:
    """Flat {column: value} of a results dataclass, nested names joined by "_": numbers as floats, flags,
    counts and words as they are, a tuple of numbers as a list."""
    out: dict[str, Any] = {}
    for f in dataclasses.fields(result):
        value = getattr(result, f.name)
        if dataclasses.is_dataclass(value):
            inner = f.metadata.get("prefix")
            out.update(columns(value, prefix + (f"{f.name}_" if inner is None else inner)))
        elif isinstance(value, (str, bool, int)):  # words, flags and counts as they are
            out[prefix + f.name] = value
        elif isinstance(value, tuple):  # a curve's points: a list in the row and the parquet table
            out[prefix + f.name] = list(value)
        else:
            out[prefix + f.name] = float(value)
    return out
