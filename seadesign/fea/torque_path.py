"""A torque-rotation path's points and how to read the curve between them: a cubic Hermite interpolant
through the converged points with their tangents dT/dtheta. SI units (rad, Nm)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from seadesign.fea.contact import NO_CONTACT, ContactSummary
from seadesign.fea.elements import ElementMesh


@dataclass(frozen=True)
class PathPoint:
    """One converged state of the path."""

    rotation_rad: float
    torque_Nm: float
    tangent_Nm_per_rad: float  # dT/dtheta
    peak_tensile_strain: float  # largest tensile principal engineering strain at the quadrature points (Solid.element_strain_stress)
    min_gap_mm: float  # smallest gap between facing surfaces (mm; inf: none within the search distance)
    iterations: int
    residual_norms_N: tuple[float, ...]
    peak_tensile_element: int = -1  # element of the peak tensile strain
    peak_compressive_strain: float = 0.0  # largest compressive principal engineering strain (1 - stretch)
    peak_compressive_element: int = -1
    peak_von_mises_Pa: float = 0.0  # largest Cauchy von Mises stress at the quadrature points
    peak_von_mises_element: int = -1
    min_gap_at_mm: tuple[float, float, float] = (float("nan"),) * 3  # where the smallest gap is (at rest)
    contact: ContactSummary = NO_CONTACT  # the contact's pressure, area and moment (a path through contact)


# why an attempt in contact failed at the smallest step (Newton's status): the event that ends the path there
UNCONVERGED_EVENTS = {"failed": "contact_unconverged", "penetrating": "unresolved_penetration",
                      "losing_energy": "contact_energy_loss"}


@dataclass(frozen=True)
class PathEvent:
    """Something on the path: its kind ("contact": facing surfaces first carry pressure; "unresolved_penetration":
    the multiplier updates could not bring the penetration within the tolerance, so the path ended unconverged,
    torque NaN; "contact_energy_loss": likewise, the hub's work and the strain energy's increase differing at every
    step size; "contact_unconverged": likewise, Newton finding no equilibrium in contact), rotation (rad), torque (Nm)
    and where (mm, the part at rest)."""

    kind: str
    rotation_rad: float
    torque_Nm: float
    at_mm: tuple[float, float, float]


@dataclass(frozen=True)
class TorquePath:
    """The path from rest to where it stopped, the stop's reason, and the last converged displacement."""

    points: tuple[PathPoint, ...]
    stop_reason: str
    stop_rotation_rad: float
    stop_torque_Nm: float
    displacement_m: np.ndarray | None = field(repr=False)  # (N, 3) at the last converged point (None: a path
    # scaled and cut short, `fea.path_scale`, or kept without its states)
    emesh: ElementMesh = field(repr=False)
    cut_backs: int = 0
    factorizations: int = 0  # tangent factorizations, cut-back attempts included
    time_s: float = 0.0
    snapshot_index: int = -1  # the point whose displacement is `snapshot_displacement_m` (see rotation_path)
    snapshot_displacement_m: np.ndarray | None = field(default=None, repr=False)
    events: tuple[PathEvent, ...] = ()

    def torque_at(self, rotation_rad: float) -> float | None:
        """Torque (Nm) at `rotation_rad` on the cubic Hermite curve through the points, None past the last."""
        for a, b in zip(self.points, self.points[1:]):
            if a.rotation_rad <= rotation_rad <= b.rotation_rad:
                return float(hermite(a, b, (rotation_rad - a.rotation_rad) / (b.rotation_rad - a.rotation_rad)))
        return None

    def rotation_at(self, torque_Nm: float) -> float | None:
        """Rotation (rad) at which the path first carries `torque_Nm` (cubic Hermite between the bracketing
        points, with their tangents), None if it never does."""
        for a, b in zip(self.points, self.points[1:]):
            if a.torque_Nm <= torque_Nm <= b.torque_Nm:
                return hermite_inverse(a, b, torque_Nm)
        return None


def hermite(a: PathPoint, b: PathPoint, s: np.ndarray | float) -> np.ndarray | float:
    """T at theta_a + s (theta_b - theta_a), s in [0, 1]: the cubic Hermite interpolant with the points' tangents."""
    h = b.rotation_rad - a.rotation_rad
    return ((2 * s**3 - 3 * s**2 + 1) * a.torque_Nm + (s**3 - 2 * s**2 + s) * h * a.tangent_Nm_per_rad
            + (-2 * s**3 + 3 * s**2) * b.torque_Nm + (s**3 - s**2) * h * b.tangent_Nm_per_rad)


def hermite_inverse(a: PathPoint, b: PathPoint, torque_Nm: float) -> float:
    """theta in [a, b] where the Hermite interpolant first equals torque_Nm (bisection; T(a) <= torque <= T(b))."""
    lo, hi = 0.0, 1.0
    for _ in range(60):
        s = 0.5 * (lo + hi)
        lo, hi = (s, hi) if hermite(a, b, s) < torque_Nm else (lo, s)
    return a.rotation_rad + 0.5 * (lo + hi) * (b.rotation_rad - a.rotation_rad)
