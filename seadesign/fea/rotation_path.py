"""The large-deflection torque-rotation path of a spring, driven by the hub's rotation.

The path is composed of parts that read alone: the hub held as the servo holds it
(`fea.hub_rotation`), the solid's equilibrium with those nodes prescribed (`fea.equilibrium`), Newton
(`fea.newton`), the facing surfaces' gap (`fea.contact`) and the events (`fea.path_events`). This
module is the continuation: each increment prescribes theta, Newton finds the free nodes from a
predicted state, and the reaction torque T(theta) is read from the internal forces on the hub nodes.
Increments adapt: a step that does not converge is cut back and retried from the last converged
state, never accepted.

The path stops, and says why (`STOP_REASONS` of `design.spring`):
- target_reached: T reached the target torque;
- limit_point: T passed a maximum below the target (dT/dtheta <= 0) while the free nodes' tangent
  stays positive definite: the torque-driven spring snaps through there; the stop is the maximum;
- bifurcation: the free nodes' tangent stiffness lost positive definiteness (an eigenvalue crossed
  zero, counted by its inertia: a buckling mode); both are located by bisection to `locate_tol_rad`
  (contact to `contact_locate_tol_rad`, then where the gap interpolates to the tolerance);
- contact, without `PathSettings.contact`: two facing surfaces (outward normals opposed by more than
  120 degrees) come closer than `contact_gap_mm` (the notch beside a beam's root closing, a beam
  reaching its neighbour); without contact forces the path ends there, interpolated to the tolerance.
  With `PathSettings.contact`, frictionless self-contact (`fea.contact`, an augmented Lagrangian)
  carries the closed gap and the path goes on: first contact is an event (`TorquePath.events`, where
  the first pressed pair's gap closes), each point records the contact's area, peak pressure, moment
  and penetration, and an increment whose penetration the multiplier updates cannot bring within
  the tolerance is cut back like one that does not converge (below `contact_min_step_rad` the path ends
  unconverged, and an "unresolved_penetration" event says where); so is an increment over which the
  hub's work and the strain energy's increase differ (`path_events.energy_balanced`: frictionless
  contact stores no energy), and where that holds at every step size a "contact_energy_loss" event
  says where; an increment in contact where Newton finds no equilibrium at the smallest step ends the path with a
  "contact_unconverged" event;
- strain_limit: the peak tensile principal engineering strain passed the allowable strain;
- rotation_limit: the rotation reached `max_rotation_rad` below the target torque;
- unconverged: the increment fell below `min_step_rad` (`contact_min_step_rad` from a point in contact)
  without convergence (never a capacity).
SI units throughout; mesh coordinates arrive in mm.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, replace

import numpy as np

from seadesign.design.materials import Hyperelastic
from seadesign.errors import NotPositiveDefinite, SolverError
from seadesign.fea.blas import one_blas_thread
from seadesign.fea.contact import NO_CONTACT, ContactSettings, ContactSurface, FrictionlessContact, Multipliers
from seadesign.fea.facing import FacingSurfaces
from seadesign.fea.elements import element_mesh
from seadesign.fea.equilibrium import Equilibrium
from seadesign.fea.finite_strain import Solid
from seadesign.fea.hub_rotation import HubRotation, moment_z
from seadesign.fea.newton import NewtonResult, NewtonSettings, newton, newton_augmented
from seadesign.fea.path_events import (bracketing_step, contact_event, contact_rotation, energy_balanced, stop_check,
                                       stop_point)
from seadesign.fea.torque_path import UNCONVERGED_EVENTS, PathEvent, PathPoint, TorquePath
from seadesign.fea.torsion import MM, surface_nodes
from seadesign.mesh.tetmesh import TetMesh

@dataclass(frozen=True)
class PathSettings:
    """Increment control and stopping rules of the rotation-driven path."""

    first_step_rad: float = 0.02
    max_step_rad: float = 0.1
    min_step_rad: float = 1e-4
    contact_min_step_rad: float = 2e-3  # the smallest step from a point in contact (first contact is approached
    # with `min_step_rad`): where a notch creases, the end found with smaller steps scatters by more than this
    # between runs, and the steps below it took most of the path's time (docs/validation/timing.md)
    max_rotation_rad: float = 6.0
    newton: NewtonSettings = NewtonSettings()
    force_rtol: float = 1e-7  # residual norm over the norm of the reaction forces
    locate_tol_rad: float = 1e-3  # bisection tolerance of a limit point's, bifurcation's or strain limit's rotation
    contact_locate_tol_rad: float = 1e-2  # bisection tolerance of contact (then interpolated in the gap)
    contact_gap_mm: float = 0.1  # a quarter of an extrusion width: printed faces are not truer than that
    contact_search_mm: float = 0.5  # below the thinnest feature: faces further apart are never checked
    allowable_strain: float | None = None  # engineering strain; None: no strain stop
    contact: ContactSettings | None = None  # frictionless self-contact through which the path goes on; None: the
    # path stops where facing surfaces come within `contact_gap_mm`


def through_contact(settings: PathSettings) -> PathSettings:
    """`settings` with frictionless self-contact; Newton gets 60 iterations an attempt, as long as the residual
    halves every 10 (`newton.stalled`): a creasing notch's active set can take that many to settle (on the 3 x 8 mm
    candidate's coarse mesh, before the energy balance, 30 ended the path unconverged at 0.558 rad and 60 reached
    0.6 rad), while an attempt whose residual wanders is cut back without spending the 60 (the 8 x 4 mm candidate's
    path mesh to its crease: 624 s instead of 1321 s, 278 factorizations instead of 626, the same end within
    0.012 rad and 0.5 % in torque)."""
    newton = replace(settings.newton, max_iterations=60, stall_window=10)
    return replace(settings, contact=ContactSettings(), newton=newton)


@dataclass
class PathProblem:
    """What one path solve holds: the hub's rotation, the free nodes' equilibrium, the facing surfaces."""

    drive: HubRotation
    system: Equilibrium
    surfaces: FacingSurfaces
    settings: PathSettings

    @property
    def solid(self) -> Solid:
        return self.system.solid


def path_problem(mesh: TetMesh, law: Hyperelastic, settings: PathSettings, order: int = 2,
                 hub_boundaries: list[str] | None = None, ring_boundaries: list[str] | None = None,
                 axially_held_faces: np.ndarray | None = None, formulation: str = "full") -> PathProblem:
    """The parts of a path on `mesh` (mm): the element mesh and its solid, the hub and ring nodes (the study's
    interfaces unless named), the free nodes' equilibrium, the surface for the gap search."""
    emesh = element_mesh(mesh.points_mm * MM, mesh.tets, order)
    hub = HubRotation.on(mesh, emesh, hub_boundaries, ring_boundaries)
    held_z = None if axially_held_faces is None else surface_nodes(emesh, axially_held_faces)
    contact = None
    if settings.contact is not None:
        contact = FrictionlessContact.of(ContactSurface.of(emesh, mesh.boundary_faces, hub.prescribed),
                                         law.shear_modulus_Pa, settings.contact)
    system = Equilibrium.of(Solid.of(emesh, law, formulation), hub.prescribed, hub.hub, settings.force_rtol, held_z,
                            contact)
    return PathProblem(hub, system, FacingSurfaces.of(emesh.nodes_m, mesh.boundary_faces, settings.contact_search_mm),
                       settings)


def _state(p: PathProblem, u: np.ndarray, f: np.ndarray, theta: float, iterations: int,
           norms: list[float]) -> tuple[PathPoint, np.ndarray]:
    """The converged point at u (internal forces f) and the path's direction du/dtheta there, from the
    tangent factored at u (NotPositiveDefinite: unstable); the next increment's Newton starts with it."""
    fac = p.system.stable_factor(u)
    v = np.zeros_like(u)
    v[p.drive.hub] = p.drive.velocity(theta)
    v[p.system.free] = -fac.solve(p.system.residual(p.system.tangent_product(u, v))).reshape(-1, 3)
    df = p.system.tangent_product(u, v, rows=p.drive.hub)  # dT/dtheta needs the hub's rows only
    xd = p.solid.mesh.nodes_m[p.drive.hub] + u[p.drive.hub]
    dT = moment_z(v[p.drive.hub], f[p.drive.hub]) + moment_z(xd, df[p.drive.hub])
    strain = p.solid.element_strain_stress(u)
    i, j, c = (int(np.argmax(x)) for x in (strain.tensile_strain, strain.von_mises_Pa, strain.compressive_strain))
    gap, gap_at = p.surfaces.min_gap_mm(u)
    contact = NO_CONTACT if p.system.contact is None else p.system.contact.summary(u)
    point = PathPoint(theta, p.drive.torque(u, f), dT, float(strain.tensile_strain[i]), gap, iterations, tuple(norms),
                      i, float(strain.compressive_strain[c]), c, float(strain.von_mises_Pa[j]), j, gap_at, contact)
    return point, v


@one_blas_thread
def rotation_path(
    mesh: TetMesh,
    law: Hyperelastic,
    target_torque_Nm: float,
    settings: PathSettings = PathSettings(),
    order: int = 2,
    hub_boundaries: list[str] | None = None,
    ring_boundaries: list[str] | None = None,
    axially_held_faces: np.ndarray | None = None,
    formulation: str = "full",
    snapshot_torque_Nm: float | None = None,
) -> TorquePath:
    """Follow T(theta) from rest until the hub torque reaches `target_torque_Nm` (Nm) or the path stops
    (see the module doc); the points are the converged increments. `axially_held_faces`: boundary
    facets (k, 3) of the mesh whose nodes keep u_z = 0 (an analytical test's plane constraint);
    `formulation`: see `fea.finite_strain`; `snapshot_torque_Nm`: also keep the displacement of the
    first point that carries this torque (Nm), or of the last point if none does (a render's state)."""
    if not target_torque_Nm > 0:
        raise SolverError(f"target_torque_Nm must be positive, got {target_torque_Nm:g}")
    t0 = time.perf_counter()
    p = path_problem(mesh, law, settings, order, hub_boundaries, ring_boundaries, axially_held_faces, formulation)
    u = np.zeros_like(p.solid.mesh.nodes_m)
    try:
        first, v = _state(p, u, np.zeros_like(u), 0.0, 0, [0.0])
        points, step, cuts, reason, previous = [first], settings.first_step_rad, 0, None, None
        snapshot, probe = None, None  # probe: the last attempt rejected for contact since the last point
        events: list[PathEvent] = []
        held = None if p.system.contact is None else p.system.contact.multipliers  # the last point's multipliers
        held_before = held  # the point's before it
        balance = (0.0, 0.0)  # the last point's strain energy (J) and contact normal force (N): `energy_balanced`
        while reason is None:
            last = points[-1]
            step = min(step, settings.max_step_rad, settings.max_rotation_rad - last.rotation_rad)
            theta = last.rotation_rad + step
            solved = _solve(p, u, v, previous, last.rotation_rad, step, theta, held, held_before)
            trial, forces, norms, status = solved.u, solved.forces, solved.residual_norms, solved.status
            event = None
            if status == "converged":
                try:
                    point, v_new = _state(p, trial, forces, theta, len(norms) - 1, norms)
                    event = stop_check(settings, last, point, target_torque_Nm)
                except NotPositiveDefinite:
                    status = "unstable"
                if status == "converged" and p.system.contact is not None:
                    trial_balance = (p.solid.energy(trial), p.system.contact.normal_force_N(trial))
                    contact_work = (balance[1] + trial_balance[1]) * settings.contact.penetration_tol_mm * 1e-3
                    if not energy_balanced(last, point, balance[0], trial_balance[0], contact_work):
                        status = "losing_energy"
            located = step <= (settings.contact_locate_tol_rad if event == "contact" else settings.locate_tol_rad)
            if status == "unstable" and located:
                reason = "bifurcation"
            elif status != "converged" or (event not in (None, "target_reached", "rotation_limit") and not located):
                # not converged, or an event (limit point, contact, strain limit) to be located more closely
                cuts += 1
                contact = None
                if event == "contact":  # the secant through the last two attempts, else through the bracket
                    estimates = (contact_rotation(a, point, settings) for a in (probe, last) if a is not None)
                    contact = next((c for c in estimates if c is not None and last.rotation_rad < c < theta), None)
                    probe = point
                step = step * 0.5 if contact is None else bracketing_step(contact, last.rotation_rad, settings)
                floor = settings.contact_min_step_rad if last.contact.area_m2 > 0 else settings.min_step_rad
                if status in ("failed", "penetrating", "losing_energy") and step < floor:
                    reason = "unconverged"
                    pressed = NO_CONTACT if p.system.contact is None else p.system.contact.summary(trial)
                    if status != "failed" or pressed.area_m2 > 0:  # where: the rotation tried, where it presses hardest
                        events.append(PathEvent(UNCONVERGED_EVENTS[status], theta, float("nan"), pressed.peak_at_mm))
            else:
                if p.system.contact is not None and not events and point.contact.area_m2 > 0:
                    events.append(contact_event(last, point, p.system.contact.closing_fraction(u, trial)))
                held_before, held = held, None if p.system.contact is None else p.system.contact.multipliers
                balance = trial_balance if p.system.contact is not None else balance
                points.append(point)
                if snapshot is None and snapshot_torque_Nm is not None and point.torque_Nm >= snapshot_torque_Nm:
                    snapshot = (len(points) - 1, trial)
                previous, probe = (u, last.rotation_rad), None
                u, v, reason = trial, v_new, event
                if len(norms) <= 8:
                    step *= 1.5
                contact = None if events else contact_rotation(last, point, settings)  # a closing gap: bracket it
                if contact is not None and contact > point.rotation_rad:
                    step = min(step, bracketing_step(contact, point.rotation_rad, settings))
    finally:
        p.system.close()
    stop_theta, stop_torque = stop_point(points, reason, target_torque_Nm, settings.contact_gap_mm)
    index, shot = snapshot or (len(points) - 1, u)
    return TorquePath(tuple(points), reason, stop_theta, stop_torque, u, p.solid.mesh, cuts, p.system.factorizations,
                      time.perf_counter() - t0, index, shot, tuple(events))


def _solve(p: PathProblem, u: np.ndarray, v: np.ndarray, previous: tuple[np.ndarray, float] | None, last_rad: float,
           step: float, theta: float, held: Multipliers | None, held_before: Multipliers | None) -> NewtonResult:
    """Newton at the hub rotation theta (rad), `step` on from the last point (u, its direction v, at `last_rad`;
    `previous`: the point before it), from `_predict`'s guess; with contact, the augmented Lagrangian from the multipliers extrapolated
    linearly from the last two converged points' (`held`, `held_before`), so that every attempt, a cut-back's too,
    starts from the converged ones."""
    guess = _predict(p, u, v, step, previous, last_rad)
    guess[p.drive.hub] = p.drive.displacement(theta)
    if p.system.contact is None:
        return newton(p.system, guess, p.settings.newton)
    p.system.contact.multipliers = held.extrapolated(held_before, step / (last_rad - previous[1]) if previous else 0.0)
    return newton_augmented(p.system, guess, p.settings.newton)


def _predict(p: PathProblem, u: np.ndarray, v: np.ndarray, step: float,
             previous: tuple[np.ndarray, float] | None, theta: float) -> np.ndarray:
    """Starting guess at theta + step: quadratic through the previous state with the tangent v, or
    from rest the tangent with its rotation about the axis taken as a rotation (nodes stay on their
    circles to second order; a straight tangent step would change volumes by step^2, which a nearly
    incompressible law answers with spurious pressures)."""
    if previous is not None:
        u_prev, theta_prev = previous
        h = theta - theta_prev
        return u + v * step + (u_prev - u + v * h) * (step / h) ** 2
    x = p.solid.mesh.nodes_m + u
    r2 = np.maximum(x[:, 0] ** 2 + x[:, 1] ** 2, 1e-30)
    omega = (x[:, 0] * v[:, 1] - x[:, 1] * v[:, 0]) / r2  # angular rate about z of each node (1/rad)
    c, s = np.cos(omega * step), np.sin(omega * step)
    swirl = np.column_stack([(c - 1) * x[:, 0] - s * x[:, 1], s * x[:, 0] + (c - 1) * x[:, 1], np.zeros(len(x))])
    rest = v - np.column_stack([-omega * x[:, 1], omega * x[:, 0], np.zeros(len(x))])
    return u + swirl + rest * step


@one_blas_thread
def rotation_sweep(mesh: TetMesh, law: Hyperelastic, rotations_rad: list[float],
                   settings: PathSettings = PathSettings(), order: int = 2) -> tuple[PathPoint, ...]:
    """The equilibria at the hub rotations `rotations_rad` (rad) in the order given, from rest: loading, then
    unloading, any sequence. Each is reached from the last point as the path reaches its next increment (the same
    predictor and, through contact, the multipliers extrapolated from the last two points), an interval that does
    not converge halved down to `settings.min_step_rad` (then SolverError, naming the rotation); no events, no
    stops. The points: rest, then one per given rotation (those a halved interval inserts are left out). A
    frictionless elastic part is reversible: unloading retraces loading (tested through contact). Rest is the start:
    a rotation of 0 has no reaction to judge convergence against, and is refused."""
    if not all(rotations_rad):
        raise SolverError("rotation_sweep starts at rest: give non-zero rotations (rad)")
    p = path_problem(mesh, law, settings, order)
    u = np.zeros_like(p.solid.mesh.nodes_m)
    try:
        point, v = _state(p, u, np.zeros_like(u), 0.0, 0, [0.0])
        points, last, previous = [point], point, None
        held = held_before = None if p.system.contact is None else p.system.contact.multipliers
        pending = [(theta, True) for theta in rotations_rad[::-1]]  # (rotation, given), the next one last
        while pending:
            theta, given = pending[-1]
            step = theta - last.rotation_rad
            solved = _solve(p, u, v, previous, last.rotation_rad, step, theta, held, held_before)
            if solved.status != "converged":
                if abs(step) / 2 < settings.min_step_rad:
                    raise SolverError(f"no equilibrium at the hub rotation {theta:.6g} rad: Newton {solved.status} "
                                      f"from {last.rotation_rad:.6g} rad with the smallest step")
                pending.append((last.rotation_rad + step / 2, False))
                continue
            point, v_new = _state(p, solved.u, solved.forces, theta, len(solved.residual_norms) - 1,
                                  solved.residual_norms)
            if p.system.contact is not None:
                held_before, held = held, p.system.contact.multipliers
            if given:
                points.append(point)
            previous, u, v, last = (u, last.rotation_rad), solved.u, v_new, point
            pending.pop()
    finally:
        p.system.close()
    return tuple(points)
