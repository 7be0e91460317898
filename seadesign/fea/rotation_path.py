"""The large-deflection torque-rotation path of a spring, driven by the hub's rotation.

The hub is held as the servo holds it: its coupled surface nodes follow x' = R(theta) x exactly
(rotation about the z axis, no translation, no tilt); the ring's coupled nodes are held. The
solve is displacement-controlled: each increment prescribes theta, Newton (with a backtracking
line search on the energy) finds the free nodes, and the reaction torque T(theta) is read from the
internal forces on the hub nodes. Increments adapt: a step that does not converge is cut back
and retried from the last converged state, never accepted.

The path stops, and says why (`STOP_REASONS` of `design.spring`):
- target_reached: T reached the target torque;
- limit_point: T passed a maximum below the target (dT/dtheta <= 0): the torque-driven spring
  snaps through there; the reported stop is the maximum;
- bifurcation: the tangent stiffness of the free nodes lost positive definiteness (its smallest
  eigenvalue reached zero: a buckling mode), located by bisection to `locate_tol_rad`;
- contact: two surface points that start apart (more than `contact_exclusion_mm`) come closer
  than `contact_gap_mm`;
- strain_limit: the peak principal engineering strain passed the allowable strain;
- unconverged: the increment fell below `min_step_rad` without convergence (never a capacity).
SI units throughout; mesh coordinates arrive in mm.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
from scipy.spatial import cKDTree

from seadesign.design.materials import Hyperelastic
from seadesign.errors import NotPositiveDefinite, SolverError
from seadesign.fea.elements import ElementMesh, element_mesh
from seadesign.fea.finite_strain import Solid
from seadesign.fea.pardiso import Pardiso
from seadesign.fea.torsion import MM, default_boundaries, surface_nodes
from seadesign.mesh.tetmesh import TetMesh


@dataclass(frozen=True)
class PathSettings:
    """Increment control and stopping rules of the rotation-driven path."""

    first_step_rad: float = 0.02
    max_step_rad: float = 0.1
    min_step_rad: float = 1e-4
    max_rotation_rad: float = 6.0
    max_iterations: int = 12
    force_rtol: float = 1e-8  # residual norm over the norm of the reaction forces
    locate_tol_rad: float = 1e-3  # bisection tolerance of a bifurcation's rotation
    contact_gap_mm: float = 0.05
    contact_exclusion_mm: float = 2.0  # surface points closer than this at rest never count as contact
    allowable_strain: float | None = None  # engineering strain; None: no strain stop


@dataclass(frozen=True)
class PathPoint:
    """One converged state of the path."""

    rotation_rad: float
    torque_Nm: float
    tangent_Nm_per_rad: float  # dT/dtheta
    peak_strain: float  # largest principal engineering strain (max stretch - 1) at the quadrature points
    min_gap_mm: float  # smallest distance between surface points that start apart (inf: none within range)
    iterations: int
    residual_norms_N: tuple[float, ...]


@dataclass(frozen=True)
class TorquePath:
    """The path from rest to where it stopped, the stop's reason, and the last converged displacement."""

    points: tuple[PathPoint, ...]
    stop_reason: str
    stop_rotation_rad: float
    stop_torque_Nm: float
    displacement_m: np.ndarray = field(repr=False)  # (N, 3) at the last converged point
    emesh: ElementMesh = field(repr=False)
    cut_backs: int = 0
    time_s: float = 0.0

    @property
    def rotation_rad(self) -> np.ndarray:
        return np.array([p.rotation_rad for p in self.points])

    @property
    def torque_Nm(self) -> np.ndarray:
        return np.array([p.torque_Nm for p in self.points])

    def rotation_at(self, torque_Nm: float) -> float | None:
        """Rotation (rad) at which the path first carries `torque_Nm` (cubic Hermite between the bracketing
        points, with their tangents), None if it never does."""
        for a, b in zip(self.points, self.points[1:]):
            if a.torque_Nm <= torque_Nm <= b.torque_Nm:
                return _hermite_inverse(a, b, torque_Nm)
        return None


@dataclass
class _Problem:
    """Numbering and fixed data of one path solve."""

    solid: Solid
    hub: np.ndarray
    free: np.ndarray
    node_index: np.ndarray
    surface: np.ndarray
    settings: PathSettings
    dof_free: np.ndarray  # (n_free, 3) 1.0 for a free degree of freedom of a free node, 0.0 for one held at zero
    pardiso: Pardiso | None = None

    def residual(self, f: np.ndarray) -> np.ndarray:
        """The out-of-balance forces (N) on the free degrees of freedom, flattened."""
        return (f[self.free] * self.dof_free).ravel()

    def hub_displacement(self, theta: float) -> np.ndarray:
        x, y = self.solid.mesh.nodes_m[self.hub, 0], self.solid.mesh.nodes_m[self.hub, 1]
        c, s = np.cos(theta), np.sin(theta)
        return np.column_stack([(c - 1) * x - s * y, s * x + (c - 1) * y, np.zeros_like(x)])

    def hub_velocity(self, theta: float) -> np.ndarray:
        """d(hub displacement)/dtheta (m/rad)."""
        x, y = self.solid.mesh.nodes_m[self.hub, 0], self.solid.mesh.nodes_m[self.hub, 1]
        c, s = np.cos(theta), np.sin(theta)
        return np.column_stack([-s * x - c * y, c * x - s * y, np.zeros_like(x)])

    def torque(self, u: np.ndarray, f: np.ndarray) -> float:
        """Reaction torque about z (Nm) that holds the hub: sum of x' x f over the hub nodes."""
        xd = self.solid.mesh.nodes_m[self.hub] + u[self.hub]
        fh = f[self.hub]
        return float(np.sum(xd[:, 0] * fh[:, 1] - xd[:, 1] * fh[:, 0]))

    def factor(self, u: np.ndarray) -> Pardiso:
        """Factorization of the free-node tangent at u (NotPositiveDefinite when it has lost stability)."""
        k = self.solid.tangent(u, self.node_index, len(self.free))
        if not self.dof_free.all():  # held degrees of freedom: zero rows and columns, unit diagonal
            m = self.dof_free
            k.values[:] *= m[k.rows][:, :, None] * m[k.cols][:, None, :]
            diag = k.rows == k.cols
            k.values[diag] += np.eye(3) * (1.0 - m[k.rows[diag]])[:, None, :]
        k = k.matrix()
        if self.pardiso is not None and self.pardiso._alive:
            try:
                self.pardiso.refactor(k)
                return self.pardiso
            except NotPositiveDefinite:
                self.pardiso = None
                raise
        self.pardiso = Pardiso(k)
        return self.pardiso

    def close(self) -> None:
        if self.pardiso is not None:
            self.pardiso.close()


def _hermite(a: PathPoint, b: PathPoint, s: np.ndarray | float) -> np.ndarray | float:
    """T at theta_a + s (theta_b - theta_a), s in [0, 1]: the cubic Hermite interpolant with the points' tangents."""
    h = b.rotation_rad - a.rotation_rad
    return ((2 * s**3 - 3 * s**2 + 1) * a.torque_Nm + (s**3 - 2 * s**2 + s) * h * a.tangent_Nm_per_rad
            + (-2 * s**3 + 3 * s**2) * b.torque_Nm + (s**3 - s**2) * h * b.tangent_Nm_per_rad)


def _hermite_inverse(a: PathPoint, b: PathPoint, torque_Nm: float) -> float:
    """theta in [a, b] where the Hermite interpolant first equals torque_Nm (bisection; T(a) <= torque <= T(b))."""
    lo, hi = 0.0, 1.0
    for _ in range(60):
        s = 0.5 * (lo + hi)
        lo, hi = (s, hi) if _hermite(a, b, s) < torque_Nm else (lo, s)
    return a.rotation_rad + 0.5 * (lo + hi) * (b.rotation_rad - a.rotation_rad)


def _min_gap_mm(p: _Problem, u: np.ndarray) -> float:
    """Smallest deformed distance (mm) between surface nodes that were further apart than the exclusion at rest."""
    s = p.settings
    xd = p.solid.mesh.nodes_m[p.surface] + u[p.surface]
    tree = cKDTree(xd)
    search = max(4.0 * s.contact_gap_mm, 0.5) * MM
    pairs = tree.query_pairs(search, output_type="ndarray")
    if len(pairs) == 0:
        return float("inf")
    x0 = p.solid.mesh.nodes_m[p.surface]
    apart = np.linalg.norm(x0[pairs[:, 0]] - x0[pairs[:, 1]], axis=1) > s.contact_exclusion_mm * MM
    if not apart.any():
        return float("inf")
    pairs = pairs[apart]
    return float(np.linalg.norm(xd[pairs[:, 0]] - xd[pairs[:, 1]], axis=1).min() / MM)


def _newton(p: _Problem, u0: np.ndarray, theta: float) -> tuple[np.ndarray, list[float], bool]:
    """Equilibrium of the free nodes at hub rotation theta from the guess u0: (u, residual norms, converged)."""
    s = p.settings
    u = u0.copy()
    u[p.hub] = p.hub_displacement(theta)
    norms: list[float] = []
    try:
        f = p.solid.forces(u)
    except FloatingPointError:
        return u, norms, False
    for _ in range(s.max_iterations):
        r = p.residual(f)
        scale = max(np.linalg.norm(f[p.hub]), 1e-12)
        norms.append(float(np.linalg.norm(r)))
        if norms[-1] <= s.force_rtol * scale:
            return u, norms, True
        try:
            du = -p.factor(u).solve(r).reshape(-1, 3)
        except (NotPositiveDefinite, FloatingPointError):
            return u, norms, False
        e0, slope = p.solid.energy(u), float(r @ du.ravel())
        alpha = 1.0
        while alpha > 1e-3:
            trial = u.copy()
            trial[p.free] += alpha * du
            try:
                e1 = p.solid.energy(trial)
                f1 = p.solid.forces(trial)
            except FloatingPointError:  # an element inverted: shorten the step
                alpha *= 0.5
                continue
            # accept when the energy falls as Armijo asks, or (near convergence, where energies
            # differ by round-off) when the residual falls
            if e1 <= e0 + 1e-4 * alpha * slope or np.linalg.norm(p.residual(f1)) < norms[-1]:
                break
            alpha *= 0.5
        else:
            return u, norms, False
        u, f = trial, f1
    norms.append(float(np.linalg.norm(p.residual(f))))
    return u, norms, norms[-1] <= s.force_rtol * max(np.linalg.norm(f[p.hub]), 1e-12)


def _state(p: _Problem, u: np.ndarray, theta: float, iterations: int, norms: list[float]) -> tuple[PathPoint, np.ndarray]:
    """The converged point at u and the path's direction du/dtheta there (NotPositiveDefinite: unstable)."""
    fac = p.factor(u)
    v = np.zeros_like(u)
    v[p.hub] = p.hub_velocity(theta)
    v[p.free] = -fac.solve(p.residual(p.solid.tangent_product(u, v))).reshape(-1, 3)
    f = p.solid.forces(u)
    df = p.solid.tangent_product(u, v)
    xd = p.solid.mesh.nodes_m[p.hub] + u[p.hub]
    dT = float(np.sum(v[p.hub, 0] * f[p.hub, 1] - v[p.hub, 1] * f[p.hub, 0])
               + np.sum(xd[:, 0] * df[p.hub, 1] - xd[:, 1] * df[p.hub, 0]))
    point = PathPoint(theta, p.torque(u, f), dT, p.solid.peak_principal_strain(u), _min_gap_mm(p, u), iterations, tuple(norms))
    return point, v


def _problem(mesh: TetMesh, law: Hyperelastic, settings: PathSettings, order: int,
             hub_boundaries: list[str] | None, ring_boundaries: list[str] | None,
             axially_held_faces: np.ndarray | None, formulation: str) -> _Problem:
    default_hub, default_ring = default_boundaries(mesh)
    emesh = element_mesh(mesh.points_mm * MM, mesh.tets, order)

    def nodes(names: list[str]) -> np.ndarray:
        mesh.boundary_nodes(names)  # a clear error when one is absent
        return surface_nodes(emesh, np.concatenate([mesh.boundary_faces[mesh.boundaries[n]] for n in names]))

    hub, ring = nodes(hub_boundaries or default_hub), nodes(ring_boundaries or default_ring)
    if np.intersect1d(hub, ring).size:
        raise SolverError("the hub and the ring surfaces share nodes; they must be separate interfaces")
    prescribed = np.union1d(hub, ring)
    free = np.setdiff1d(np.arange(len(emesh.nodes_m)), prescribed)
    index = np.full(len(emesh.nodes_m), -1, dtype=np.int64)
    index[free] = np.arange(len(free))
    surface = surface_nodes(emesh, mesh.boundary_faces)
    dof_free = np.ones((len(free), 3))
    if axially_held_faces is not None:
        held = index[surface_nodes(emesh, axially_held_faces)]
        dof_free[held[held >= 0], 2] = 0.0
    return _Problem(Solid.of(emesh, law, formulation), hub, free, index, surface, settings, dof_free)


def _stop_check(p: _Problem, prev: PathPoint, point: PathPoint, target_Nm: float) -> str | None:
    s = p.settings
    if point.torque_Nm >= target_Nm:
        return "target_reached"
    if point.tangent_Nm_per_rad <= 0 or point.torque_Nm <= prev.torque_Nm:
        return "limit_point"
    if point.min_gap_mm < s.contact_gap_mm:
        return "contact"
    if s.allowable_strain is not None and point.peak_strain > s.allowable_strain:
        return "strain_limit"
    if point.rotation_rad >= s.max_rotation_rad:
        return "unconverged"
    return None


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
) -> TorquePath:
    """Follow T(theta) from rest until the hub torque reaches `target_torque_Nm` (Nm) or the path stops
    (see the module doc); the points are the converged increments. `axially_held_faces`: boundary
    facets (k, 3) of the mesh whose nodes keep u_z = 0 (an analytical test's plane constraint);
    `formulation`: see `fea.finite_strain`."""
    if not target_torque_Nm > 0:
        raise SolverError(f"target_torque_Nm must be positive, got {target_torque_Nm:g}")
    t0 = time.perf_counter()
    p = _problem(mesh, law, settings, order, hub_boundaries, ring_boundaries, axially_held_faces, formulation)
    u = np.zeros_like(p.solid.mesh.nodes_m)
    try:
        first, v = _state(p, u, 0.0, 0, [0.0])
        points, step, cuts, reason, previous = [first], settings.first_step_rad, 0, None, None
        while reason is None:
            last = points[-1]
            step = min(step, settings.max_step_rad, settings.max_rotation_rad - last.rotation_rad)
            theta = last.rotation_rad + step
            trial, norms, ok = _newton(p, _predict(p, u, v, step, previous, last.rotation_rad), theta)
            point = None
            if ok:
                try:
                    point, v_new = _state(p, trial, theta, len(norms) - 1, norms)
                except NotPositiveDefinite:
                    if step <= settings.locate_tol_rad:
                        reason = "bifurcation"
                        break
            if point is None:
                cuts += 1
                step *= 0.5
                if ok or step >= settings.min_step_rad:
                    continue
                reason = "unconverged"
                break
            points.append(point)
            previous = (u, last.rotation_rad)
            u, v = trial, v_new
            reason = _stop_check(p, last, point, target_torque_Nm)
            if len(norms) <= 5:
                step *= 1.5
    finally:
        p.close()
    stop_theta, stop_torque = _stop_point(points, reason, target_torque_Nm)
    return TorquePath(tuple(points), reason, stop_theta, stop_torque, u, p.solid.mesh, cuts, time.perf_counter() - t0)


def _predict(p: _Problem, u: np.ndarray, v: np.ndarray, step: float,
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


def _stop_point(points: list[PathPoint], reason: str, target_Nm: float) -> tuple[float, float]:
    """Where the path stops: the target torque's rotation, the torque maximum of a limit point, else the last point."""
    last = points[-1]
    if reason == "target_reached" and len(points) > 1:
        return _hermite_inverse(points[-2], last, target_Nm), target_Nm
    if reason == "limit_point" and len(points) > 1:
        a, b = points[-2], last
        s = np.linspace(0.0, 1.0, 201)
        t = _hermite(a, b, s)
        i = int(np.argmax(t))
        return a.rotation_rad + s[i] * (b.rotation_rad - a.rotation_rad), float(t[i])
    return last.rotation_rad, last.torque_Nm
