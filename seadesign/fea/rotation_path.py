"""The large-deflection torque-rotation path of a spring, driven by the hub's rotation.

The hub is held as the servo holds it: its coupled surface nodes follow x' = R(theta) x exactly
(rotation about the z axis, no translation, no tilt); the ring's coupled nodes are held. The
solve is displacement-controlled: each increment prescribes theta, Newton (with a backtracking
line search on the energy) finds the free nodes, and the reaction torque T(theta) is read from the
internal forces on the hub nodes. Increments adapt: a step that does not converge is cut back
and retried from the last converged state, never accepted.

The path stops, and says why (`STOP_REASONS` of `design.spring`):
- target_reached: T reached the target torque;
- limit_point: T passed a maximum below the target (dT/dtheta <= 0) while the free nodes' tangent
  stays positive definite: the torque-driven spring snaps through there; the stop is the maximum;
- bifurcation: the free nodes' tangent stiffness lost positive definiteness (an eigenvalue crossed
  zero, counted by its inertia: a buckling mode); both are located by bisection to `locate_tol_rad`
  (contact to `contact_locate_tol_rad`, then where the gap interpolates to the tolerance);
- contact: two facing surfaces (outward normals opposed by more than 120 degrees) come closer
  than `contact_gap_mm` (the notch beside a beam's root closing, a beam reaching its neighbour);
  the model has no contact forces, so the path ends there, interpolated to the tolerance;
- strain_limit: the peak tensile principal engineering strain passed the allowable strain;
- rotation_limit: the rotation reached `max_rotation_rad` below the target torque;
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
from seadesign.fea.assembly import PairPattern
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
    max_iterations: int = 30
    force_rtol: float = 1e-7  # residual norm over the norm of the reaction forces
    refresh_ratio: float = 0.5  # Newton refactors the tangent when an iteration cuts the residual by less than this
    locate_tol_rad: float = 1e-3  # bisection tolerance of a limit point's, bifurcation's or strain limit's rotation
    contact_locate_tol_rad: float = 1e-2  # bisection tolerance of contact (then interpolated in the gap)
    contact_gap_mm: float = 0.1  # a quarter of an extrusion width: printed faces are not truer than that
    contact_search_mm: float = 0.5  # below the thinnest feature: faces further apart are never checked
    allowable_strain: float | None = None  # engineering strain; None: no strain stop


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
    factorizations: int = 0  # tangent factorizations, cut-back attempts included
    time_s: float = 0.0
    snapshot_index: int = -1  # the point whose displacement is `snapshot_displacement_m` (see rotation_path)
    snapshot_displacement_m: np.ndarray | None = field(default=None, repr=False)

    def torque_at(self, rotation_rad: float) -> float | None:
        """Torque (Nm) at `rotation_rad` on the cubic Hermite curve through the points, None past the last."""
        for a, b in zip(self.points, self.points[1:]):
            if a.rotation_rad <= rotation_rad <= b.rotation_rad:
                return float(_hermite(a, b, (rotation_rad - a.rotation_rad) / (b.rotation_rad - a.rotation_rad)))
        return None

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
    surface: np.ndarray  # boundary vertices (contact is checked on the linear facets)
    boundary_faces: np.ndarray
    rest_normals: np.ndarray  # outward unit normals of the boundary vertices at rest
    settings: PathSettings
    dof_free: np.ndarray  # (n_free, 3) 1.0 for a free degree of freedom of a free node, 0.0 for one held at zero
    pattern: PairPattern  # where the tangent's element blocks land (free nodes only)
    pardiso: Pardiso | None = None  # the factorization last made
    factorizations: int = 0

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
        return moment_z(self.solid.mesh.nodes_m[self.hub] + u[self.hub], f[self.hub])

    def converged(self, f: np.ndarray, residual_norm: float) -> bool:
        """Whether the out-of-balance force is within the tolerance of the hub's reaction forces."""
        return residual_norm <= self.settings.force_rtol * max(float(np.linalg.norm(f[self.hub])), 1e-12)

    def factor(self, u: np.ndarray) -> Pardiso:
        """LDL^T factorization of the free-node tangent at u; NotPositiveDefinite when its inertia counts a
        negative eigenvalue (the state has lost stability). The inertia is exact, where a Cholesky
        factorization near a singular point may or may not meet its negative pivot."""
        k = self.solid.tangent(u, self.pattern)
        self._hold(k)
        k = k.matrix()
        if self.pardiso is not None and self.pardiso.alive:
            self.pardiso.refactor(k)
        else:
            self.pardiso = Pardiso(k, indefinite=True)
        self.factorizations += 1
        if self.pardiso.inertia()[1] > 0:
            raise NotPositiveDefinite("the tangent stiffness has a negative eigenvalue")
        return self.pardiso

    def _hold(self, k) -> None:
        """Held degrees of freedom: zero rows and columns, unit diagonal (in place)."""
        if not self.dof_free.all():
            m = self.dof_free
            k.values[:] *= m[k.rows][:, :, None] * m[k.cols][:, None, :]
            diag = k.rows == k.cols
            k.values[diag] += np.eye(3) * (1.0 - m[k.rows[diag]])[:, None, :]

    def close(self) -> None:
        if self.pardiso is not None:
            self.pardiso.close()


def moment_z(x: np.ndarray, f: np.ndarray) -> float:
    """z component of sum x x f (Nm) over rows of positions x (m) and forces f (N)."""
    return float(np.sum(x[:, 0] * f[:, 1] - x[:, 1] * f[:, 0]))


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


def _vertex_normals(x: np.ndarray, faces: np.ndarray, vertices: np.ndarray) -> np.ndarray:
    """Unit outward normals (area-weighted) of the boundary vertices at positions x."""
    tri = x[faces]
    normal = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    vn = np.zeros_like(x)
    for k in range(3):
        np.add.at(vn, faces[:, k], normal)
    return vn[vertices] / np.linalg.norm(vn[vertices], axis=1)[:, None]


def _gap(x: np.ndarray, n: np.ndarray, pairs: np.ndarray) -> np.ndarray:
    """Separation of vertex pairs along their normals (m); positive across open space, negative through material."""
    d = x[pairs[:, 1]] - x[pairs[:, 0]]
    return 0.5 * np.einsum("ij,ij->i", d, n[pairs[:, 0]] - n[pairs[:, 1]])


def _min_gap_mm(p: _Problem, u: np.ndarray) -> tuple[float, tuple[float, float, float]]:
    """Smallest gap (mm) between facing boundary vertices of the deformed part, and where (the pair's
    midpoint at rest, mm; NaN without a pair): pairs within the search distance whose outward normals
    are opposed (cosine < -0.5) and that faced each other across open space at rest (not the two sides
    of a thin wall); the gap is their separation along the normals, negative once they overlap."""
    x0 = p.solid.mesh.nodes_m[p.surface]
    x = x0 + u[p.surface]
    n = _vertex_normals(p.solid.mesh.nodes_m + u, p.boundary_faces, p.surface)
    pairs = cKDTree(x).query_pairs(p.settings.contact_search_mm * MM, output_type="ndarray")
    if len(pairs):
        pairs = pairs[np.einsum("ij,ij->i", n[pairs[:, 0]], n[pairs[:, 1]]) < -0.5]
    if len(pairs):
        pairs = pairs[_gap(x0, p.rest_normals, pairs) > 0]
    if not len(pairs):
        return float("inf"), (float("nan"),) * 3
    gaps = _gap(x, n, pairs)
    k = int(np.argmin(gaps))
    return float(gaps[k] / MM), tuple(float(c) for c in x0[pairs[k]].mean(axis=0) / MM)


def _newton(p: _Problem, u0: np.ndarray, theta: float) -> tuple[np.ndarray, np.ndarray | None, list[float], str]:
    """Equilibrium of the free nodes at hub rotation theta from the guess u0: (u, its internal forces,
    residual norms, status) with status "converged", "unstable" (a tangent that is not positive
    definite) or "failed".

    Newton's method with the tangent refactored only when needed: between refactorizations the tangent
    last factored (the previous converged state's, or after a cut-back the rejected attempt's) is
    corrected by BFGS updates from the iterations since (Matthies and Strang's quasi-Newton method for
    finite elements). It is refactored at the current iterate when an iteration cuts the residual by
    less than `refresh_ratio`, or its direction finds no descent. A backtracking line search on the
    energy guards every step."""
    u = u0.copy()
    u[p.hub] = p.hub_displacement(theta)
    norms: list[float] = []
    try:
        f = p.solid.forces(u)
    except FloatingPointError:
        return u, None, norms, "failed"
    r = p.residual(f)
    fresh = False  # the held factorization is of the current iterate
    refresh = p.pardiso is None or not p.pardiso.alive
    updates: list[tuple[np.ndarray, np.ndarray, float]] = []  # BFGS pairs (s, y, 1 / y.s) since the factorization
    for _ in range(p.settings.max_iterations):
        norms.append(float(np.linalg.norm(r)))
        if p.converged(f, norms[-1]):
            return u, f, norms, "converged"
        if refresh and not fresh:
            try:
                p.factor(u)
            except NotPositiveDefinite:
                return u, f, norms, "unstable"
            fresh, updates = True, []
        trial, f1 = _line_search(p, u, f, r, -_bfgs_solve(p.pardiso, r, updates).reshape(-1, 3), norms[-1])
        if trial is None:
            if fresh:
                return u, f, norms, "failed"
            refresh = True
            norms.pop()
            continue
        r1 = p.residual(f1)
        step, change = (trial[p.free] - u[p.free]).ravel(), r1 - r
        curvature = float(step @ change)
        if curvature > 0:
            updates.append((step, change, 1.0 / curvature))
        refresh = float(np.linalg.norm(r1)) > p.settings.refresh_ratio * norms[-1]
        u, f, r, fresh = trial, f1, r1, False
    norms.append(float(np.linalg.norm(r)))
    return u, f, norms, "converged" if p.converged(f, norms[-1]) else "failed"


def _bfgs_solve(factorization: Pardiso, r: np.ndarray, updates: list[tuple[np.ndarray, np.ndarray, float]]) -> np.ndarray:
    """H r with H the inverse of the factored tangent corrected by the BFGS pairs (the two-loop recursion)."""
    q, alphas = r.copy(), []
    for s, y, rho in reversed(updates):
        alphas.append(rho * float(s @ q))
        q -= alphas[-1] * y
    z = factorization.solve(q)
    for (s, y, rho), alpha in zip(updates, reversed(alphas)):
        z += (alpha - rho * float(y @ z)) * s
    return z


def _line_search(p: _Problem, u: np.ndarray, f: np.ndarray, r: np.ndarray, du: np.ndarray,
                 norm: float) -> tuple[np.ndarray | None, np.ndarray | None]:
    """u + alpha du for the first alpha in 1, 1/2, ... 1/1000 whose residual norm is below `norm`, else whose
    energy falls as Armijo asks; (None, None) when none does."""
    e0, slope = None, float(r @ du.ravel())
    alpha = 1.0
    while alpha > 1e-3:
        trial = u.copy()
        trial[p.free] += alpha * du
        try:
            f1 = p.solid.forces(trial)
            if np.linalg.norm(p.residual(f1)) < norm:
                return trial, f1
            e0 = p.solid.energy(u) if e0 is None else e0
            if p.solid.energy(trial) <= e0 + 1e-4 * alpha * slope:
                return trial, f1
        except FloatingPointError:  # an element inverted: shorten the step
            pass
        alpha *= 0.5
    return None, None


def _state(p: _Problem, u: np.ndarray, f: np.ndarray, theta: float, iterations: int,
           norms: list[float]) -> tuple[PathPoint, np.ndarray]:
    """The converged point at u (internal forces f) and the path's direction du/dtheta there, from the
    tangent factored at u (NotPositiveDefinite: unstable); the next increment's Newton starts with it."""
    fac = p.factor(u)
    v = np.zeros_like(u)
    v[p.hub] = p.hub_velocity(theta)
    v[p.free] = -fac.solve(p.residual(p.solid.tangent_product(u, v))).reshape(-1, 3)
    df = p.solid.tangent_product(u, v, rows=p.hub)  # dT/dtheta needs the hub's rows only
    xd = p.solid.mesh.nodes_m[p.hub] + u[p.hub]
    dT = moment_z(v[p.hub], f[p.hub]) + moment_z(xd, df[p.hub])
    strain = p.solid.element_strain_stress(u)
    i, j, c = (int(np.argmax(x)) for x in (strain.tensile_strain, strain.von_mises_Pa, strain.compressive_strain))
    gap, gap_at = _min_gap_mm(p, u)
    point = PathPoint(theta, p.torque(u, f), dT, float(strain.tensile_strain[i]), gap, iterations, tuple(norms),
                      i, float(strain.compressive_strain[c]), c, float(strain.von_mises_Pa[j]), j, gap_at)
    return point, v


def path_problem(mesh: TetMesh, law: Hyperelastic, settings: PathSettings, order: int,
                 hub_boundaries: list[str] | None, ring_boundaries: list[str] | None,
                 axially_held_faces: np.ndarray | None, formulation: str) -> _Problem:
    """The numbering and fixed data of a path on `mesh` (mm): the element mesh, the hub and ring nodes
    (the study's interfaces unless named), the free nodes, the surface for contact (the CalculiX check
    drives and holds the same nodes)."""
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
    surface = np.unique(mesh.boundary_faces)
    dof_free = np.ones((len(free), 3))
    if axially_held_faces is not None:
        held = index[surface_nodes(emesh, axially_held_faces)]
        dof_free[held[held >= 0], 2] = 0.0
    rest_normals = _vertex_normals(emesh.nodes_m, mesh.boundary_faces, surface)
    return _Problem(Solid.of(emesh, law, formulation), hub, free, index, surface, mesh.boundary_faces, rest_normals,
                    settings, dof_free, PairPattern.of(emesh.elements, order, index, len(free)))


def _stop_check(p: _Problem, prev: PathPoint, point: PathPoint, target_Nm: float) -> str | None:
    """Why the path stops at `point`, if it does; events that end the curve before the target come first,
    so that the one met first is located (the caller cuts the step until it is)."""
    s = p.settings
    if point.tangent_Nm_per_rad <= 0 or point.torque_Nm <= prev.torque_Nm:
        return "limit_point"
    if point.min_gap_mm < s.contact_gap_mm:
        return "contact"
    if s.allowable_strain is not None and point.peak_tensile_strain > s.allowable_strain:
        return "strain_limit"
    if point.torque_Nm >= target_Nm:
        return "target_reached"
    if point.rotation_rad >= s.max_rotation_rad:
        return "rotation_limit"
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
        while reason is None:
            last = points[-1]
            step = min(step, settings.max_step_rad, settings.max_rotation_rad - last.rotation_rad)
            theta = last.rotation_rad + step
            trial, forces, norms, status = _newton(p, _predict(p, u, v, step, previous, last.rotation_rad), theta)
            event = None
            if status == "converged":
                try:
                    point, v_new = _state(p, trial, forces, theta, len(norms) - 1, norms)
                    event = _stop_check(p, last, point, target_torque_Nm)
                except NotPositiveDefinite:
                    status = "unstable"
            located = step <= (settings.contact_locate_tol_rad if event == "contact" else settings.locate_tol_rad)
            if status == "unstable" and located:
                reason = "bifurcation"
            elif status != "converged" or (event not in (None, "target_reached", "rotation_limit") and not located):
                # not converged, or an event (limit point, contact, strain limit) to be located more closely
                cuts += 1
                contact = None
                if event == "contact":  # the secant through the last two attempts, else through the bracket
                    estimates = (_contact_rotation(a, point, settings) for a in (probe, last) if a is not None)
                    contact = next((c for c in estimates if c is not None and last.rotation_rad < c < theta), None)
                    probe = point
                step = step * 0.5 if contact is None else _bracketing_step(contact, last.rotation_rad, settings)
                if status == "failed" and step < settings.min_step_rad:
                    reason = "unconverged"
            else:
                points.append(point)
                if snapshot is None and snapshot_torque_Nm is not None and point.torque_Nm >= snapshot_torque_Nm:
                    snapshot = (len(points) - 1, trial)
                previous, probe = (u, last.rotation_rad), None
                u, v, reason = trial, v_new, event
                if len(norms) <= 8:
                    step *= 1.5
                contact = _contact_rotation(last, point, settings)  # a closing gap: bracket where it closes
                if contact is not None and contact > point.rotation_rad:
                    step = min(step, _bracketing_step(contact, point.rotation_rad, settings))
    finally:
        p.close()
    stop_theta, stop_torque = _stop_point(points, reason, target_torque_Nm, settings.contact_gap_mm)
    index, shot = snapshot or (len(points) - 1, u)
    return TorquePath(tuple(points), reason, stop_theta, stop_torque, u, p.solid.mesh, cuts, p.factorizations,
                      time.perf_counter() - t0, index, shot)


def _contact_rotation(a: PathPoint, b: PathPoint, s: PathSettings) -> float | None:
    """Where the gap, linear through a and b, reaches `contact_gap_mm` (rad); None unless both gaps are
    finite and differ."""
    if not (np.isfinite(a.min_gap_mm) and np.isfinite(b.min_gap_mm)) or a.min_gap_mm == b.min_gap_mm:
        return None
    return a.rotation_rad + (a.min_gap_mm - s.contact_gap_mm) / (a.min_gap_mm - b.min_gap_mm) * (b.rotation_rad - a.rotation_rad)


def _bracketing_step(contact_rad: float, theta: float, s: PathSettings) -> float:
    """The step from theta toward a predicted contact: 0.3 of the locating tolerance short of it when it lies
    further than the tolerance, else as far past it (within the tolerance, so that the bracket locates it)."""
    tol, ahead = s.contact_locate_tol_rad, contact_rad - theta
    return ahead - 0.3 * tol if ahead > tol else min(tol, ahead + 0.3 * tol)


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


def _stop_point(points: list[PathPoint], reason: str, target_Nm: float, gap_mm: float) -> tuple[float, float]:
    """Where the path stops: the target torque's rotation, the torque maximum of a limit point, contact
    where the gap (linear between the last two points) reaches `gap_mm`, else the last point."""
    last = points[-1]
    if reason == "target_reached" and len(points) > 1:
        return _hermite_inverse(points[-2], last, target_Nm), target_Nm
    if reason == "limit_point" and len(points) > 1:
        a, b = points[-2], last
        s = np.linspace(0.0, 1.0, 201)
        t = _hermite(a, b, s)
        i = int(np.argmax(t))
        return a.rotation_rad + s[i] * (b.rotation_rad - a.rotation_rad), float(t[i])
    if reason == "contact" and len(points) > 1 and np.isfinite(points[-2].min_gap_mm):
        a, b = points[-2], last
        s = float(np.clip((a.min_gap_mm - gap_mm) / (a.min_gap_mm - b.min_gap_mm), 0.0, 1.0))
        return a.rotation_rad + s * (b.rotation_rad - a.rotation_rad), float(_hermite(a, b, s))
    return last.rotation_rad, last.torque_Nm
