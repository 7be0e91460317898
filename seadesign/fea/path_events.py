"""Events on a torque-rotation path and where the path ends: which event a converged point shows, where
a closing gap is predicted to reach the contact tolerance (to bracket it), and the stop's rotation and
torque read from the last points. The reasons are `STOP_REASONS` of `design.spring`."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from seadesign.fea.torque_path import PathEvent, PathPoint, hermite, hermite_inverse

if TYPE_CHECKING:
    from seadesign.fea.rotation_path import PathSettings


def stop_check(s: PathSettings, prev: PathPoint, point: PathPoint, target_Nm: float) -> str | None:
    """Why the path stops at `point`, if it does; events that end the curve before the target come first,
    so that the one met first is located (the caller cuts the step until it is)."""
    if point.tangent_Nm_per_rad <= 0 or point.torque_Nm <= prev.torque_Nm:
        return "limit_point"
    if s.contact is None and point.min_gap_mm < s.contact_gap_mm:
        return "contact"
    if s.allowable_strain is not None and point.peak_tensile_strain > s.allowable_strain:
        return "strain_limit"
    if point.torque_Nm >= target_Nm:
        return "target_reached"
    if point.rotation_rad >= s.max_rotation_rad:
        return "rotation_limit"
    return None


def touching_gap_mm(s: PathSettings) -> float:
    """The gap (mm) at which surfaces touch: zero with contact forces, else the gap at which the path stops."""
    return s.contact_gap_mm if s.contact is None else 0.0


def contact_rotation(a: PathPoint, b: PathPoint, s: PathSettings) -> float | None:
    """Where the gap, linear through a and b, reaches `touching_gap_mm` (rad); None unless both gaps are
    finite and differ."""
    if not (np.isfinite(a.min_gap_mm) and np.isfinite(b.min_gap_mm)) or a.min_gap_mm == b.min_gap_mm:
        return None
    return a.rotation_rad + (a.min_gap_mm - touching_gap_mm(s)) / (a.min_gap_mm - b.min_gap_mm) * (b.rotation_rad - a.rotation_rad)


def contact_event(a: PathPoint, b: PathPoint, fraction: float) -> PathEvent:
    """Contact first carrying pressure `fraction` of the way from a to b (see `FrictionlessContact.closing_fraction`):
    its rotation, the torque there on the curve, and where the pressure peaks at b."""
    theta = a.rotation_rad + fraction * (b.rotation_rad - a.rotation_rad)
    return PathEvent("contact", theta, float(hermite(a, b, fraction)), b.contact.peak_at_mm)


def bracketing_step(contact_rad: float, theta: float, s: PathSettings) -> float:
    """The step from theta toward a predicted contact: 0.3 of the locating tolerance short of it when it lies
    further than the tolerance, else as far past it (within the tolerance, so that the bracket locates it)."""
    tol, ahead = s.contact_locate_tol_rad, contact_rad - theta
    return ahead - 0.3 * tol if ahead > tol else min(tol, ahead + 0.3 * tol)


def stop_point(points: list[PathPoint], reason: str, target_Nm: float, gap_mm: float) -> tuple[float, float]:
    """Where the path stops: the target torque's rotation, the torque maximum of a limit point, contact
    where the gap (linear between the last two points) reaches `gap_mm`, else the last point."""
    last = points[-1]
    if reason == "target_reached" and len(points) > 1:
        return hermite_inverse(points[-2], last, target_Nm), target_Nm
    if reason == "limit_point" and len(points) > 1:
        a, b = points[-2], last
        s = np.linspace(0.0, 1.0, 201)
        t = hermite(a, b, s)
        i = int(np.argmax(t))
        return a.rotation_rad + s[i] * (b.rotation_rad - a.rotation_rad), float(t[i])
    if reason == "contact" and len(points) > 1 and np.isfinite(points[-2].min_gap_mm):
        a, b = points[-2], last
        s = float(np.clip((a.min_gap_mm - gap_mm) / (a.min_gap_mm - b.min_gap_mm), 0.0, 1.0))
        return a.rotation_rad + s * (b.rotation_rad - a.rotation_rad), float(hermite(a, b, s))
    return last.rotation_rad, last.torque_Nm


def energy_balanced(a: PathPoint, b: PathPoint, energy_a_J: float, energy_b_J: float, contact_work_J: float) -> bool:
    """Whether the hub's work from a to b equals the strain energy's increase from `energy_a_J` to `energy_b_J`
    (J), as frictionless contact asks (it stores no energy of its own). The work is the integral of the cubic
    Hermite curve through the two points; allowed: 4 times that quadrature's error scale (its difference from
    the trapezoid, h^2 / 12 |T'a - T'b|, Nm rad), the work the contact forces may do within the penetration
    tolerance (`contact_work_J`: the normal forces at a and b times the tolerance) and 1e-6 of the energy at b
    (Newton's tolerance). A curve whose tangent jumps inside the step (contact onset) passes at any step (the
    rule's error there is at most |kink|); energy lost in a jump fails once the steps are small, the shape's
    allowance shrinking as h^2."""
    h = b.rotation_rad - a.rotation_rad
    kink = h * h / 12 * (a.tangent_Nm_per_rad - b.tangent_Nm_per_rad)
    work = h / 2 * (a.torque_Nm + b.torque_Nm) + kink
    return abs(work - (energy_b_J - energy_a_J)) <= 4 * abs(kink) + contact_work_J + 1e-6 * abs(energy_b_J)
