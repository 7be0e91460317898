"""Typed FEA results, units in the field names, each quantity with its rule for the applied torque.

Every number is a dataclass field made by `linear()`, `inverse()` or `unscaled()`: how it changes
when the load case's torque T is multiplied by s (x s, / s, unchanged). A linear solve's fields also
name how they change when every modulus is multiplied by s at the same Poisson ratio (`modulus=`): the
torque is applied through rigid couplings, so stresses and reactions do not depend on the modulus,
rotations and displacements go as 1 / s and k as s. Fields that hold another results dataclass are
scaled through their own fields. `scaled` and `with_modulus` apply the rules and refuse a field without
one; `columns` flattens a result into the results table's columns
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


def linear(modulus: Scaling | None = None) -> Any:
    return field(metadata={"scaling": Scaling.LINEAR, "modulus": modulus})


def inverse(modulus: Scaling | None = None) -> Any:
    return field(metadata={"scaling": Scaling.INVERSE, "modulus": modulus})


def unscaled(modulus: Scaling | None = None) -> Any:
    return field(metadata={"scaling": Scaling.NONE, "modulus": modulus})


def nested(prefix: str | None = None) -> Any:
    """A field holding a results dataclass; its columns are named `<prefix><inner name>`
    (default prefix: `<field name>_`)."""
    return field(metadata={"prefix": prefix})


@dataclass(frozen=True)
class StressPeak:
    """The peak of one stress measure over the nodes (MPa) and where it is (part frame, mm)."""

    MPa: float = linear(Scaling.NONE)
    x_mm: float = unscaled(Scaling.NONE)
    y_mm: float = unscaled(Scaling.NONE)
    z_mm: float = unscaled(Scaling.NONE)


@dataclass(frozen=True)
class PeakStresses:
    """The peak stresses of one load case, and the safety factor against yield they give."""

    von_mises_max: StressPeak = nested()
    principal_1_max: StressPeak = nested()
    principal_3_min: StressPeak = nested()
    max_shear_max: StressPeak = nested()
    safety_factor: float = inverse(Scaling.NONE)  # yield strength / peak von Mises


@dataclass(frozen=True)
class StallResult:
    """Stall torque on the hub, ring held."""

    torque_Nm: float = linear(Scaling.NONE)
    rotation_rad: float = linear(Scaling.INVERSE)
    bearing_displacement_mm: float = linear(Scaling.INVERSE)  # largest displacement on the bearing circle
    stresses: PeakStresses = nested("")


@dataclass(frozen=True)
class ImpactResult:
    """Impact torque on the ring (backplate side), hub held; reactions on the hub bolts."""

    torque_Nm: float = linear(Scaling.NONE)
    reaction_per_bolt_N: float = linear(Scaling.NONE)  # largest resultant force on one hub bolt's coupling
    reaction_per_bolt_min_N: float = linear(Scaling.NONE)
    bolt_count: float = unscaled(Scaling.NONE)
    peak_nodal_reaction_N: float = linear(Scaling.NONE)  # largest single nodal force (mesh dependent)
    stresses: PeakStresses = nested("")


@dataclass(frozen=True)
class SolveStats:
    """How the solve was made: element order, sizes, mesh quality, timings (s)."""

    element_order: float = unscaled(Scaling.NONE)
    dofs: float = unscaled(Scaling.NONE)
    mesh_nodes: float = unscaled(Scaling.NONE)
    mesh_tets: float = unscaled(Scaling.NONE)
    mesh_min_dihedral_deg: float = unscaled(Scaling.NONE)
    mesh_max_aspect_ratio: float = unscaled(Scaling.NONE)
    time_setup_s: float = unscaled(Scaling.NONE)
    time_assembly_s: float = unscaled(Scaling.NONE)
    time_factorization_s: float = unscaled(Scaling.NONE)
    time_solve_s: float = unscaled(Scaling.NONE)
    time_stress_s: float = unscaled(Scaling.NONE)


@dataclass(frozen=True)
class LinearResults:
    """Both load cases of the linear model from one factorization."""

    k_Nm_per_rad: float = unscaled(Scaling.LINEAR)
    equilibrium_rel_error: float = unscaled(Scaling.NONE)  # |reaction torque + applied torque| / applied torque
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

    def with_modulus(self, factor: float) -> "LinearResults":
        """The same solve with every modulus `factor` times larger (the same Poisson ratio)."""
        return with_modulus(self, factor)

    def at(self, stall_torque_Nm: float, impact_torque_Nm: float) -> "LinearResults":
        """The same solve at other (positive) load-case torques: each case scaled by its own ratio."""
        return replace(self, stall=scaled(self.stall, stall_torque_Nm / self.stall.torque_Nm),
                       impact=scaled(self.impact, impact_torque_Nm / self.impact.torque_Nm))


def scaled(result: Any, factor: float) -> Any:
    """`result` with every field changed by its rule for a torque `factor` (> 0) times larger."""
    return _rescaled(result, factor, "scaling", "torque")


def with_modulus(result: Any, factor: float) -> Any:
    """`result` with every field changed by its rule for moduli `factor` (> 0) times larger."""
    return _rescaled(result, factor, "modulus", "modulus")


def _rescaled(result: Any, factor: float, key: str, what: str) -> Any:
    if not factor > 0:
        raise ValueError(f"{what} factor must be positive, got {factor}")
    changes = {}
    for f in dataclasses.fields(result):
        value = getattr(result, f.name)
        if dataclasses.is_dataclass(value):
            changes[f.name] = _rescaled(value, factor, key, what)
            continue
        rule = f.metadata.get(key)
        if rule is None:
            raise TypeError(f"{type(result).__name__}.{f.name} has no {what}-scaling rule; declare it in its "
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
