"""The large-deflection numbers of a spring at the study's torques, read from its torque path.

A path (`fea.rotation_path`) is one curve T(theta) from rest to where it stops; this module reads
it at the standing, stall and impact torques: the rotation there, secant and tangent stiffness, the
peak strain and its margin against the allowable strain, and whether the part survives that load.
A curve does not scale with torque (every field is `unscaled()`); where it stops depends on the
target torque, which is therefore part of the path's cache key.

A load the path does not reach is not read off an extrapolation: its rotation is NaN and the part
does not survive it, unless the path stopped at contact and the study treats contact as an end stop
(the closed gap carries the rest of the torque: the rotation is the contact rotation, and the
strain there decides). Strains are engineering principal strains (largest stretch - 1), linear in
rotation between the path's points.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from seadesign.fea.results import nested, unscaled
from seadesign.fea.rotation_path import TorquePath


@dataclass(frozen=True)
class LoadPoint:
    """The path at one load torque."""

    torque_Nm: float = unscaled()
    reached: bool = unscaled()  # the path carries the torque before any stop
    rotation_rad: float = unscaled()  # NaN when not reached (the contact rotation when contact is an end stop)
    secant_k_Nm_per_rad: float = unscaled()  # torque / rotation
    tangent_k_Nm_per_rad: float = unscaled()  # dT/dtheta there (NaN at an end stop)
    peak_strain: float = unscaled()  # largest principal engineering strain in the part at that rotation
    strain_margin: float = unscaled()  # allowable strain / peak strain (NaN without an allowable strain)
    survives: bool = unscaled()  # carried (reached or at an end stop) with the peak strain within the allowable


@dataclass(frozen=True)
class PeakLocation:
    """Where a peak or a contact sits in the part frame (mm): the centroid of the peak's element, the
    midpoint of the closing pair."""

    x_mm: float = unscaled()
    y_mm: float = unscaled()
    z_mm: float = unscaled()


@dataclass(frozen=True)
class LargeDeflection:
    """One candidate's torque path read at its loads; the curve's points and how the solve went."""

    curve_rotation_rad: tuple[float, ...] = unscaled()
    curve_torque_Nm: tuple[float, ...] = unscaled()
    stop_reason: str = unscaled()  # see fea.rotation_path
    stop_rotation_rad: float = unscaled()
    stop_torque_Nm: float = unscaled()
    contact_rotation_rad: float = unscaled()  # NaN: no contact on the path
    contact_torque_Nm: float = unscaled()
    contact_at: PeakLocation = nested()  # the closing pair's midpoint at rest (NaN: no contact)
    allowable_strain: float = unscaled()  # NaN: the material has no sourced elongation at yield
    strain_limit_rotation_rad: float = unscaled()  # where the peak strain passes the allowable (NaN: never)
    strain_limit_torque_Nm: float = unscaled()
    peak_strain: float = unscaled()  # over the whole path (engineering: largest stretch - 1)
    peak_log_strain: float = unscaled()  # the same peak as a logarithmic strain, ln(stretch)
    peak_strain_at: PeakLocation = nested()
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
    """First rotation where `values` (linear between points) reaches `level`; NaN if never."""
    above = np.flatnonzero(values >= level)
    if not above.size:
        return math.nan
    i = int(above[0])
    if i == 0:
        return float(theta[0])
    s = (level - values[i - 1]) / (values[i] - values[i - 1])
    return float(theta[i - 1] + s * (theta[i] - theta[i - 1]))


def _location(path: TorquePath, element: int) -> PeakLocation:
    x = path.emesh.nodes_m[path.emesh.elements[element, :4]].mean(axis=0) * 1e3
    return PeakLocation(*map(float, x))


def _load_point(path: TorquePath, theta: np.ndarray, strain: np.ndarray, torque_Nm: float, allowable: float,
                contact_is_end_stop: bool) -> LoadPoint:
    """The path at one load torque; `theta` and `strain` are its points' rotations (rad) and peak strains."""
    rotation = path.rotation_at(torque_Nm)
    reached = rotation is not None and rotation <= path.stop_rotation_rad
    tangent = math.nan
    if reached:
        tangent = float(np.interp(rotation, theta, [p.tangent_Nm_per_rad for p in path.points]))
    elif contact_is_end_stop and path.stop_reason == "contact" and torque_Nm > path.stop_torque_Nm:
        rotation = path.stop_rotation_rad
    else:
        rotation = math.nan
    peak = float(np.interp(rotation, theta, strain)) if math.isfinite(rotation) else math.nan
    return LoadPoint(
        torque_Nm=torque_Nm,
        reached=bool(reached),
        rotation_rad=float(rotation),
        secant_k_Nm_per_rad=torque_Nm / rotation if math.isfinite(rotation) and rotation > 0 else math.nan,
        tangent_k_Nm_per_rad=tangent,
        peak_strain=peak,
        strain_margin=allowable / peak if math.isfinite(allowable) and peak > 0 else math.nan,
        survives=bool(math.isfinite(peak) and not (peak > allowable)),
    )


def large_deflection(path: TorquePath, standing_torque_Nm: float, stall_torque_Nm: float, impact_torque_Nm: float,
                     allowable_strain: float | None, contact_is_end_stop: bool = False) -> LargeDeflection:
    """The path read at the standing, stall and impact torques (Nm); `allowable_strain` (engineering
    strain, None: unknown) decides survival; see the module doc for a load the path does not reach."""
    pts = path.points
    allowable = math.nan if allowable_strain is None else float(allowable_strain)
    theta = np.array([p.rotation_rad for p in pts])
    torque = np.array([p.torque_Nm for p in pts])
    strain = np.array([p.peak_strain for p in pts])
    contact = path.stop_reason == "contact"
    limit_theta = _crossing(theta, strain, allowable) if math.isfinite(allowable) else math.nan
    worst_strain = max(pts, key=lambda p: p.peak_strain)
    worst_stress = max(pts, key=lambda p: p.peak_von_mises_Pa)
    return LargeDeflection(
        curve_rotation_rad=tuple(map(float, theta)),
        curve_torque_Nm=tuple(map(float, torque)),
        stop_reason=path.stop_reason,
        stop_rotation_rad=path.stop_rotation_rad,
        stop_torque_Nm=path.stop_torque_Nm,
        contact_rotation_rad=path.stop_rotation_rad if contact else math.nan,
        contact_torque_Nm=path.stop_torque_Nm if contact else math.nan,
        contact_at=PeakLocation(*pts[-1].min_gap_at_mm) if contact else PeakLocation(math.nan, math.nan, math.nan),
        allowable_strain=allowable,
        strain_limit_rotation_rad=limit_theta,
        strain_limit_torque_Nm=float(np.interp(limit_theta, theta, torque)) if math.isfinite(limit_theta) else math.nan,
        peak_strain=worst_strain.peak_strain,
        peak_log_strain=math.log1p(worst_strain.peak_strain),
        peak_strain_at=_location(path, worst_strain.peak_strain_element),
        peak_von_mises_MPa=worst_stress.peak_von_mises_Pa * 1e-6,
        peak_von_mises_at=_location(path, worst_stress.peak_von_mises_element),
        standing=_load_point(path, theta, strain, standing_torque_Nm, allowable, contact_is_end_stop),
        stall=_load_point(path, theta, strain, stall_torque_Nm, allowable, contact_is_end_stop),
        impact=_load_point(path, theta, strain, impact_torque_Nm, allowable, contact_is_end_stop),
        increments=len(pts) - 1,
        newton_iterations=sum(p.iterations for p in pts),
        cut_backs=path.cut_backs,
        dofs=3 * len(path.emesh.nodes_m),
        time_s=path.time_s,
    )
