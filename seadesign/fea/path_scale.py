"""A path under its law scaled by s: every modulus times s (and every compressibility over s).

The strain energy then scales by s at every displacement, so the equilibria of the hub's rotations are the same
displacements: torques, tangents, stresses, contact pressures and forces scale by s, and rotations, strains, gaps
and penetrations do not. Every decision the path makes is scale-free (Newton's tolerance is relative to the
reaction, the line search and the energy balance compare energies, the contact penalty follows the shear modulus,
stability reads the tangent's inertia) except those about torques: the target, and which point's state is kept.
So the path of the law times s to a target T is the path of the law itself to T / s (keeping the state at the
snapshot torque / s), its torques times s: to the last digit, whichever of the two is solved. A path already
solved to another target serves wherever its points are those: it stopped for a scale-free reason before that
target (`stop_check` tests the target after the scale-free events), or it is cut where it first reaches it. The
numbers agree with a path solved under the scaled law to round-off (tested); the computation's counts
(cut-backs, factorizations, time) stay those of the path it was read from.
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
    """`path` under its law times `s` (> 0), driven to `target_torque_Nm` (Nm): to the last digit, `path`'s own
    law driven to `target_torque_Nm / s` (keeping the snapshot at `snapshot_torque_Nm / s`), its torques then
    times s. None where `path` cannot serve: it stopped at its own target before reaching that one, or (with
    `snapshot_torque_Nm`, Nm) the point that first carries it (else the last) is not the point whose displacement
    `path` kept. `contact_gap_mm`: the path's `PathSettings.contact_gap_mm`, where a contact stop is read. A path
    cut short at the target has no last displacement (`displacement_m` None)."""
    if not s > 0:
        raise ValueError(f"a law's scale must be positive, got {s!r}")
    limit, points, last = target_torque_Nm / s, list(path.points), len(path.points) - 1
    reached = next((i for i, p in enumerate(points) if p.torque_Nm >= limit), None)
    if reached is None:
        if path.stop_reason == "target_reached":
            return None
        reason = path.stop_reason
    elif reached < last or path.stop_reason not in ("limit_point", "contact", "strain_limit"):
        reason, points = "target_reached", points[: reached + 1]  # the scale-free events are tested first
    else:
        reason = path.stop_reason
    cut = len(points) < len(path.points)
    if snapshot_torque_Nm is not None and \
            next((i for i, p in enumerate(points) if p.torque_Nm >= snapshot_torque_Nm / s), len(points) - 1) \
            != path.snapshot_index:
        return None
    stop_rad, stop_Nm = stop_point(points, reason, limit, contact_gap_mm)  # as `rotation_path` reads it
    events = tuple(replace(e, torque_Nm=s * e.torque_Nm) for e in path.events
                   if reason != "target_reached" or e.rotation_rad <= points[-1].rotation_rad)
    return TorquePath(tuple(_point(p, s) for p in points), reason, stop_rad, s * stop_Nm,
                      None if cut else path.displacement_m, path.emesh, path.cut_backs, path.factorizations,
                      path.time_s, path.snapshot_index, path.snapshot_displacement_m, events)
