"""The large-deflection numbers of a spring at the study's torques, read from its torque path.

A path (`fea.rotation_path`) is one curve T(theta) from rest to where it stops; this module reads
it at the standing, stall and impact torques: the rotation there, secant and tangent stiffness, the
tensile and compressive peak strains and the tensile margin against the load class's strain limit, and whether the part survives that load.
A curve does not scale with torque (every field is `unscaled()`); where it stops depends on the
target torque, which is therefore part of the path's cache key.

A load the path does not reach is not read off an extrapolation: its rotation is NaN and the part
does not survive it, unless the path stopped at contact and the study treats contact as an end stop
(the closed gap carries the rest of the torque: the rotation is the contact rotation, and the
strain there decides). Strains are tensile and compressive principal engineering strains, told apart by
the sign of the principal Cauchy stress (`fea.finite_strain.principal_strains`), linear in rotation
between the path's points. The repeating loads (standing, stall) are judged against the cyclic strain
limit, the impact against the single-event one (`StrainLimits`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from seadesign.design.materials import StrainLimits
from seadesign.fea.results import nested, unscaled
from seadesign.fea.torque_path import UNCONVERGED_EVENTS, PathEvent, TorquePath


@dataclass(frozen=True)
class PeakLocation:
    """Where a peak or a contact sits in the part frame (mm): the centroid of the peak's element, the
    midpoint of the closing pair."""

    x_mm: float = unscaled()
    y_mm: float = unscaled()
    z_mm: float = unscaled()


NOWHERE = PeakLocation(math.nan, math.nan, math.nan)


@dataclass(frozen=True)
class LoadPoint:
    """The path at one load torque."""

    torque_Nm: float = unscaled()
    reached: bool = unscaled()  # the path carries the torque before any stop
    rotation_rad: float = unscaled()  # NaN when not reached (the contact rotation when contact is an end stop)
    secant_k_Nm_per_rad: float = unscaled()  # torque / rotation
    tangent_k_Nm_per_rad: float = unscaled()  # dT/dtheta there (NaN at an end stop)
    tensile_strain: float = unscaled()  # largest tensile principal engineering strain in the part at that rotation
    tensile_at: PeakLocation = nested()  # where it is (at the nearest path point)
    compressive_strain: float = unscaled()  # largest compressive principal engineering strain (1 - stretch)
    compressive_at: PeakLocation = nested()
    contact_share: float = unscaled()  # the pair forces' moment about the axis over the torque (0: no contact)
    strain_limit: float = unscaled()  # the allowable tensile strain of this load's class (NaN: not sourced)
    strain_margin: float = unscaled()  # strain limit / tensile strain (NaN without a limit)
    survives: bool = unscaled()  # carried (reached or at an end stop) with the tensile strain within a sourced limit


@dataclass(frozen=True)
class LargeDeflection:
    """One candidate's torque path read at its loads; the curve's points and how the solve went."""

    curve_rotation_rad: tuple[float, ...] = unscaled()
    curve_torque_Nm: tuple[float, ...] = unscaled()
    curve_tangent_Nm_per_rad: tuple[float, ...] = unscaled()  # dT/dtheta at each point
    curve_tensile_strain: tuple[float, ...] = unscaled()  # the part's largest tensile principal strain at each point
    stop_reason: str = unscaled()  # see fea.rotation_path
    stop_rotation_rad: float = unscaled()
    stop_torque_Nm: float = unscaled()
    contact_rotation_rad: float = unscaled()  # first contact (the path's stop, or its event through contact); NaN: none
    contact_torque_Nm: float = unscaled()
    contact_at: PeakLocation = nested()  # the closing pair's midpoint at rest, or through contact where the first
    # contact's pressure peaks (NaN: no contact)
    peak_contact_pressure_MPa: float = unscaled()  # the largest contact pressure on the path (0: none carried)
    unconverged_cause: str = unscaled()  # why contact ended the path unconverged (the event's kind, see
    # fea.torque_path.PathEvent); "": it did not
    unconverged_rotation_rad: float = unscaled()  # the rotation tried there (NaN: none)
    unconverged_at: PeakLocation = nested()  # where the contact pressed hardest there (NaN: none)
    cyclic_strain_limit: float = unscaled()  # NaN: the material has no sourced cyclic strain limit
    single_strain_limit: float = unscaled()  # elongation at yield / safety factor (NaN: not sourced)
    cyclic_limit_rotation_rad: float = unscaled()  # where the tensile strain passes the cyclic limit (NaN: never)
    cyclic_limit_torque_Nm: float = unscaled()
    single_limit_rotation_rad: float = unscaled()  # where it passes the single-event limit (NaN: never)
    single_limit_torque_Nm: float = unscaled()
    peak_tensile_strain: float = unscaled()  # over the whole path
    peak_tensile_at: PeakLocation = nested()
    peak_compressive_strain: float = unscaled()  # over the whole path (1 - stretch)
    peak_compressive_at: PeakLocation = nested()
    peak_von_mises_MPa: float = unscaled()  # Cauchy von Mises, over the whole path
    peak_von_mises_at: PeakLocation = nested()
    standing: LoadPoint = nested()
    stall: LoadPoint = nested()
    impact: LoadPoint = nested()
    increments: int = unscaled()
    newton_iterations: int = unscaled()
    cut_backs: int = unscaled()
    dofs: int = unscaled()
    time_s: float = unscaled()


def _crossing(theta: np.ndarray, values: np.ndarray, level: float) -> float:
    """First rotation where `values` (linear between points) reaches `level`; NaN if never (or no level)."""
    above = np.flatnonzero(values >= level) if math.isfinite(level) else np.array([], dtype=int)
    if not above.size:
        return math.nan
    i = int(above[0])
    if i == 0:
        return float(theta[0])
    s = (level - values[i - 1]) / (values[i] - values[i - 1])
    return float(theta[i - 1] + s * (theta[i] - theta[i - 1]))


def element_location(path: TorquePath, element: int) -> PeakLocation:
    """The centroid (mm, at rest) of the path mesh's element `element` (NOWHERE for -1)."""
    if element < 0:
        return NOWHERE
    x = path.emesh.nodes_m[path.emesh.elements[element, :4]].mean(axis=0) * 1e3
    return PeakLocation(*map(float, x))


def _nan(value: float | None) -> float:
    return math.nan if value is None else float(value)


def _load_point(path: TorquePath, theta: np.ndarray, torque_Nm: float, limit: float) -> LoadPoint:
    """The path at one load torque; `theta` are its points' rotations (rad), `limit` the load class's
    allowable tensile strain (NaN: none)."""
    rotation = path.rotation_at(torque_Nm)
    reached = rotation is not None and rotation <= path.stop_rotation_rad
    tangent = math.nan
    if reached:
        tangent = float(np.interp(rotation, theta, [p.tangent_Nm_per_rad for p in path.points]))
    else:
        rotation = math.nan
    carried = math.isfinite(rotation)
    tensile = compressive = share = math.nan
    tensile_at = compressive_at = NOWHERE
    if carried:
        tensile = float(np.interp(rotation, theta, [p.peak_tensile_strain for p in path.points]))
        compressive = float(np.interp(rotation, theta, [p.peak_compressive_strain for p in path.points]))
        share = float(np.interp(rotation, theta, [p.contact.moment_Nm for p in path.points])) / torque_Nm
        near = path.points[int(np.argmin(np.abs(theta - rotation)))]
        tensile_at = element_location(path, near.peak_tensile_element)
        compressive_at = element_location(path, near.peak_compressive_element)
    return LoadPoint(
        torque_Nm=torque_Nm,
        reached=bool(reached),
        rotation_rad=float(rotation),
        secant_k_Nm_per_rad=torque_Nm / rotation if carried and rotation > 0 else math.nan,
        tangent_k_Nm_per_rad=tangent,
        tensile_strain=tensile,
        tensile_at=tensile_at,
        compressive_strain=compressive,
        compressive_at=compressive_at,
        contact_share=share,
        strain_limit=limit,
        strain_margin=limit / tensile if math.isfinite(limit) and tensile > 0 else math.nan,
        survives=bool(carried and tensile <= limit),  # False where the limit is not sourced (NaN)
    )


def large_deflection(path: TorquePath, standing_torque_Nm: float, stall_torque_Nm: float, impact_torque_Nm: float,
                     limits: StrainLimits) -> LargeDeflection:
    """The path read at the standing, stall and impact torques (Nm) against the load classes' strain `limits`;
    see the module doc for a load the path does not reach."""
    pts = path.points
    cyclic, single = _nan(limits.cyclic), _nan(limits.single)
    theta = np.array([p.rotation_rad for p in pts])
    torque = np.array([p.torque_Nm for p in pts])
    tensile = np.array([p.peak_tensile_strain for p in pts])
    first_contact = next((e for e in path.events if e.kind == "contact"), None)
    end = path.events[-1] if path.events and path.events[-1].kind in UNCONVERGED_EVENTS.values() else None
    if first_contact is None and path.stop_reason == "contact":
        first_contact = PathEvent("contact", path.stop_rotation_rad, path.stop_torque_Nm, pts[-1].min_gap_at_mm)

    def limit_torque(rotation: float) -> float:
        return float(np.interp(rotation, theta, torque)) if math.isfinite(rotation) else math.nan

    cyclic_theta, single_theta = _crossing(theta, tensile, cyclic), _crossing(theta, tensile, single)
    worst_tension = max(pts, key=lambda p: p.peak_tensile_strain)
    worst_compression = max(pts, key=lambda p: p.peak_compressive_strain)
    worst_stress = max(pts, key=lambda p: p.peak_von_mises_Pa)
    return LargeDeflection(
        curve_rotation_rad=tuple(map(float, theta)),
        curve_torque_Nm=tuple(map(float, torque)),
        curve_tangent_Nm_per_rad=tuple(float(p.tangent_Nm_per_rad) for p in pts),
        curve_tensile_strain=tuple(map(float, tensile)),
        stop_reason=path.stop_reason,
        stop_rotation_rad=path.stop_rotation_rad,
        stop_torque_Nm=path.stop_torque_Nm,
        contact_rotation_rad=first_contact.rotation_rad if first_contact else math.nan,
        contact_torque_Nm=first_contact.torque_Nm if first_contact else math.nan,
        contact_at=PeakLocation(*first_contact.at_mm) if first_contact else NOWHERE,
        peak_contact_pressure_MPa=max(p.contact.peak_pressure_Pa for p in pts) * 1e-6,
        unconverged_cause=end.kind if end else "",
        unconverged_rotation_rad=end.rotation_rad if end else math.nan,
        unconverged_at=PeakLocation(*end.at_mm) if end else NOWHERE,
        cyclic_strain_limit=cyclic,
        single_strain_limit=single,
        cyclic_limit_rotation_rad=cyclic_theta,
        cyclic_limit_torque_Nm=limit_torque(cyclic_theta),
        single_limit_rotation_rad=single_theta,
        single_limit_torque_Nm=limit_torque(single_theta),
        peak_tensile_strain=worst_tension.peak_tensile_strain,
        peak_tensile_at=element_location(path, worst_tension.peak_tensile_element),
        peak_compressive_strain=worst_compression.peak_compressive_strain,
        peak_compressive_at=element_location(path, worst_compression.peak_compressive_element),
        peak_von_mises_MPa=worst_stress.peak_von_mises_Pa * 1e-6,
        peak_von_mises_at=element_location(path, worst_stress.peak_von_mises_element),
        standing=_load_point(path, theta, standing_torque_Nm, cyclic),
        stall=_load_point(path, theta, stall_torque_Nm, cyclic),
        impact=_load_point(path, theta, impact_torque_Nm, single),
        increments=len(pts) - 1,
        newton_iterations=sum(p.iterations for p in pts),
        cut_backs=path.cut_backs,
        dofs=3 * len(path.emesh.nodes_m),
        time_s=path.time_s,
    )
