"""A path under its law scaled by s: every modulus times s (and every compressibility over s).

The strain energy then scales by s at every displacement, so the equilibria of the hub's rotations are the same
displacements: torques, tangents, stresses, contact pressures and forces scale by s, and rotations, strains, gaps
and penetrations do not. Every decision the path makes is scale-free (Newton's tolerance is relative to the
reaction, the line search and the energy balance compare energies, the contact penalty follows the shear modulus,
stability reads the tangent's inertia) except the target torque. So a path computed once serves a calibration that
scales the law: its points up to where s T first reaches the target, which is where the scaled path itself would
have stopped (`stop_check` tests the target after the scale-free events). A base path that reached its target
cannot serve a softer law (the scaled curve would need to go on), and says so by returning None. The numbers agree
with a path computed under the scaled law to round-off (tested); the computation's counts (cut-backs,
factorizations, time) stay those of the path it was scaled from.
"""

from __future__ import annotations

from dataclasses import replace

from seadesign.fea.path_events import stop_point
from seadesign.fea.torque_path import PathPoint, TorquePath


def _point(p: PathPoint, s: float) -> PathPoint:
    c = p.contact
    return replace(p, torque_Nm=s * p.torque_Nm, tangent_Nm_per_rad=s * p.tangent_Nm_per_rad,
                   residual_norms_N=tuple(s * x for x in p.residual_norms_N), peak_von_mises_Pa=s * p.peak_von_mises_Pa,
                   contact=replace(c, peak_pressure_Pa=s * c.peak_pressure_Pa, moment_Nm=s * c.moment_Nm))


def scaled_path(path: TorquePath, s: float, target_torque_Nm: float, contact_gap_mm: float,
                snapshot_torque_Nm: float | None = None) -> TorquePath | None:
    """`path` under its law times `s` (> 0), driven to `target_torque_Nm` (Nm), as `rotation_path` would have found
    it; None where it cannot serve: it stopped at its own target before the scaled curve reaches this one, or (with
    `snapshot_torque_Nm`, Nm) the scaled path's snapshot (the first point carrying that torque, else the last) is
    not the point whose displacement `path` kept. `contact_gap_mm`: the path's `PathSettings.contact_gap_mm`, where
    a contact stop is read. A path cut short at the target has no last displacement (`displacement_m` None)."""
    if not s > 0:
        raise ValueError(f"a law's scale must be positive, got {s!r}")
    points = [_point(p, s) for p in path.points]
    last = len(points) - 1
    reached = next((i for i, p in enumerate(points) if p.torque_Nm >= target_torque_Nm), None)
    if reached is None:
        if path.stop_reason == "target_reached":
            return None
        reason = path.stop_reason
    elif reached < last or path.stop_reason not in ("limit_point", "contact", "strain_limit"):
        reason, points = "target_reached", points[: reached + 1]  # the scale-free events are tested first
    else:
        reason = path.stop_reason
    scaled = TorquePath(tuple(points), reason, *stop_point(points, reason, target_torque_Nm, contact_gap_mm),
                        path.displacement_m if len(points) == len(path.points) else None, path.emesh, path.cut_backs,
                        path.factorizations, path.time_s, path.snapshot_index, path.snapshot_displacement_m,
                        tuple(replace(e, torque_Nm=s * e.torque_Nm) for e in path.events
                              if reason != "target_reached" or e.rotation_rad <= points[-1].rotation_rad))
    if snapshot_torque_Nm is not None and snapshot_index(scaled, snapshot_torque_Nm) != path.snapshot_index:
        return None
    return scaled


def snapshot_index(path: TorquePath, snapshot_torque_Nm: float) -> int:
    """The point `rotation_path` keeps as its snapshot: the first that carries `snapshot_torque_Nm` (Nm), else the
    last."""
    return next((i for i, p in enumerate(path.points) if p.torque_Nm >= snapshot_torque_Nm), len(path.points) - 1)
