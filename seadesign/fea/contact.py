"""Frictionless self-contact of a part's boundary (quadratic tetrahedral meshes): the Gauss points of its 6-node
faces against flat facets, each pair's gap and its exact derivatives, and the contact as an energy enforced by an
augmented Lagrangian (`ContactSettings`, `FrictionlessContact`); the search's first pass is over the facing
vertices (`fea.facing`). Positions in m, pressures in Pa.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.spatial import cKDTree

from seadesign.errors import ConfigError, SolverError
from seadesign.fea.contact_geometry import FACE_POINTS, FACE_WEIGHTS, SUBFACETS, face_shape_values, plane_gap
from seadesign.fea.elements import ElementMesh, midside_nodes
from seadesign.fea.facing import FacingSurfaces
from seadesign.fea.torsion import MM


# A point faces a facet when the cosine between its face's normal and the facet's is below this (more than 107
# degrees apart): surfaces that close on each other meet nearly opposed; a wall beside a flat face (90 degrees)
# is not paired with it, which keeps the search from pairing every side-wall point with the large top and
# bottom facets of an extruded part
FACING_COSINE = -0.3
# The search's first pass pairs vertices whose (averaged) normals are more than 60 degrees apart: at an edge or
# a corner a vertex's normal leans half-way to the side wall's
NEAR_COSINE = 0.5


@dataclass(frozen=True)
class ContactSettings:
    """Frictionless contact by an augmented Lagrangian: penalty stiffness `penalty_factor` times the law's
    shear modulus over the mean boundary edge length (Pa/m), multipliers updated until no pair under pressure
    penetrates, or is held open by its multiplier, by more than `penetration_tol_mm` (`FrictionlessContact.gap_error_m`),
    at most `max_augmentations` times an increment.

    The tangent (`FrictionlessContact.tangent_blocks`) is the exact second derivative of the contact energy: the
    normal stiffness w eps grad g grad g and the pressure's geometric part - w t hess g, without which Newton
    converges only linearly once the contact carries load."""

    penalty_factor: float = 100.0
    penetration_tol_mm: float = 0.0045  # 1 % of the default study's 0.45 mm fillet radius; bounds `gap_error_m`
    max_augmentations: int = 30
    search_mm: float = 0.1  # beyond a facet's reach (its largest centroid-to-corner distance), how far from its
    # centroid a point is paired with it: more than any gap that can carry pressure; and how far behind its plane:
    # a point deeper than that entered the facet's prism from the side (at a fold), it did not cross the facet
    near_mm: float = 1.0  # the search looks only at faces with a corner vertex this close to a vertex it faces
    # (`NEAR_COSINE`, a gap at rest: a cheap first pass over the vertices; above the in-plane size of the faces
    # where surfaces close)

    def __post_init__(self) -> None:
        for key in ("penalty_factor", "penetration_tol_mm", "search_mm", "near_mm"):
            if not getattr(self, key) > 0:
                raise ConfigError(f"contact setting {key} must be positive, got {getattr(self, key)!r}")
        if self.max_augmentations < 1:
            raise ConfigError(f"contact setting max_augmentations must be at least 1, got {self.max_augmentations!r}")


@dataclass(frozen=True)
class ContactSurface:
    """The boundary of a quadratic tetrahedral mesh for contact: its 6-node faces (corners, then the midsides
    of edges 01, 12, 20), their flat facets (four a face), the faces' Gauss points and weights (rest area, m^2).

    One pass: where two faces i and j meet, the Gauss points of one are checked against the facets of the
    other, never both ways (two passes over-constrain the contact and share its load arbitrarily). The
    points of a face whose nodes are all prescribed (a held or driven surface) are never checked; between
    two faces with free nodes, those of the lower-numbered face are."""

    nodes_m: np.ndarray
    faces: np.ndarray  # (k, 6)
    facets: np.ndarray  # (4k, 3) node ids, outward
    weights_m2: np.ndarray  # (6k,) Gauss point weights, face-major
    shape: np.ndarray  # (6, 6) shape functions at the Gauss points [point, node]
    rest_points_m: np.ndarray  # (6k, 3)
    checked: np.ndarray  # (k,) bool: the face has a free node, so its points are checked
    checked_points: np.ndarray  # the Gauss points of the checked faces

    @classmethod
    def of(cls, emesh: ElementMesh, boundary_faces: np.ndarray, prescribed: np.ndarray) -> "ContactSurface":
        """The surface of `emesh` on its linear boundary facets (k, 3); `prescribed`: node ids held or driven."""
        if emesh.order != 2:
            raise SolverError("contact needs quadratic (order 2) elements")
        c = boundary_faces
        mids = [midside_nodes(emesh, c[:, i], c[:, j]) for i, j in ((0, 1), (1, 2), (2, 0))]
        faces = np.column_stack([c, *mids])
        facets = faces[:, SUBFACETS].reshape(-1, 3)
        x = emesh.nodes_m
        area = 0.5 * np.linalg.norm(np.cross(x[c[:, 1]] - x[c[:, 0]], x[c[:, 2]] - x[c[:, 0]]), axis=1)
        shape = face_shape_values(FACE_POINTS)
        checked = ~np.isin(faces, prescribed).all(axis=1)
        return cls(x, faces, facets, (area[:, None] * FACE_WEIGHTS).ravel(), shape, _points(shape, x, faces), checked,
                   np.flatnonzero(np.repeat(checked, len(FACE_WEIGHTS))))

    def points(self, u: np.ndarray, which: np.ndarray | None = None) -> np.ndarray:
        """(6k, 3) Gauss points (m) of the surface deformed by u; only those numbered `which` if given."""
        if which is None:
            return _points(self.shape, self.nodes_m + u, self.faces)
        return np.einsum("pa,pai->pi", self.shape[which % len(FACE_WEIGHTS)],
                         (self.nodes_m + u)[self.faces[which // len(FACE_WEIGHTS)]])


def _points(shape: np.ndarray, x: np.ndarray, faces: np.ndarray) -> np.ndarray:
    return np.einsum("qa,kai->kqi", shape, x[faces]).reshape(-1, 3)


@dataclass(frozen=True)
class ContactPairs:
    """Each Gauss point paired with the facet it faces (the nearest plane it projects inside), its gap (m,
    negative: penetration) and the pair's nine nodes (the point's face's six, the facet's three)."""

    point: np.ndarray
    facet: np.ndarray
    gap_m: np.ndarray
    nodes: np.ndarray  # (P, 9)
    coefficients: np.ndarray  # (P, 3, 9): (d, e1, e2) = coefficients @ node positions


@dataclass(frozen=True)
class ContactSummary:
    """Contact at one state: the rest area under pressure (m^2), the largest pressure (Pa, per rest area) and where
    (its point at rest, mm), the sum of the absolute moments about z of the pair forces (Nm: the torque that
    crosses contact) and the largest penetration (m)."""

    area_m2: float
    peak_pressure_Pa: float
    peak_at_mm: tuple[float, float, float]
    moment_Nm: float
    penetration_m: float


NO_CONTACT = ContactSummary(0.0, 0.0, (float("nan"),) * 3, 0.0, 0.0)


@dataclass(frozen=True)
class Multipliers:
    """The augmented Lagrangian's multipliers (Pa), one a (point, facet) pair, kept by the pair's key
    point * facets + facet (sorted); a pair not kept has none."""

    keys: np.ndarray
    values_Pa: np.ndarray

    @classmethod
    def none(cls) -> "Multipliers":
        return cls(np.empty(0, dtype=np.int64), np.empty(0))

    def extrapolated(self, before: "Multipliers", ratio: float) -> "Multipliers":
        """These multipliers plus `ratio` times their change since `before` (a pair `before` lacks had 0), none
        below 0: a predictor of the next increment's, as the path's displacements are predicted."""
        if ratio == 0 or not len(self.keys):
            return self
        return Multipliers(self.keys, np.maximum(self.values_Pa + ratio * (self.values_Pa - before.at(self.keys)), 0.0))

    def at(self, keys: np.ndarray) -> np.ndarray:
        """The multipliers of the pairs `keys` (0 for a pair not kept)."""
        if not len(self.keys):
            return np.zeros(len(keys))
        i = np.minimum(np.searchsorted(self.keys, keys), len(self.keys) - 1)
        return np.where(self.keys[i] == keys, self.values_Pa[i], 0.0)


@dataclass
class FrictionlessContact:
    """Frictionless self-contact of a part's boundary as an energy: each Gauss point of a face, paired with every
    flat facet it faces across open space (normals more than 107 degrees apart now: `FACING_COSINE`, the point in
    front of the facet's plane at rest, the facet not on the point's face) and projects inside, stores
    w / (2 eps) (max(0, lam - eps g)^2 - lam^2) with g its distance from the facet's plane, w its rest weight, eps
    the penalty (Pa/m) and lam the pair's multiplier (Pa): the contact pressure is max(0, lam - eps g). Exact
    forces and tangent of that energy. A point that projects inside two facets (the valley of a concave surface
    or inside a ridge of a convex one) is pushed out of both planes: it penetrates where it is behind either
    (a valley) or behind both (a ridge, seen from outside its prisms diverge)."""

    surface: ContactSurface
    settings: ContactSettings
    penalty_Pa_per_m: float
    vertices: FacingSurfaces  # the surface's corner vertices, for the search's first pass
    multipliers: Multipliers = field(repr=False)
    assignment: tuple[np.ndarray, np.ndarray] | None = field(default=None, repr=False)  # (points, facets): `search`

    @classmethod
    def of(cls, surface: ContactSurface, shear_modulus_Pa: float, settings: ContactSettings) -> "FrictionlessContact":
        edges = surface.nodes_m[surface.facets] - np.roll(surface.nodes_m[surface.facets], 1, axis=1)
        h = float(np.linalg.norm(edges, axis=2).mean())
        return cls(surface, settings, settings.penalty_factor * shear_modulus_Pa / h,
                   FacingSurfaces.of(surface.nodes_m, surface.faces[:, :3], settings.near_mm), Multipliers.none())

    def search(self, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The Gauss points paired with facets at u (m): (points, facets). Assigned (`assignment`), the pairs hold
        until the next assignment, so that the contact energy is smooth in between: a point's gap is its distance
        from its facet's plane, extended past the facet's edges. Candidates, on the faces with a corner within
        `near_mm` of a vertex it faces: a point within a facet's reach (its largest centroid-to-corner distance plus
        `search_mm`) of its centroid and less than `search_mm` behind its plane, the point in front of the facet's
        plane at rest, the point checked against the facet (see `ContactSurface`: never its own face's); of these,
        a point is paired with each facet it projects inside whose normal faces its face's (`FACING_COSINE`). A facet
        whose face shares a node with the point's is paired too: where a notch's flanks meet at its root, leaving
        those out let a point sink unseen into the other flank until it reached a facet without a shared node, which
        then pressed it out with energy the hub never put in."""
        s = self.surface
        near = np.isin(s.faces[:, :3], self.vertices.facing_vertices(u, self.settings.near_mm * MM, NEAR_COSINE))
        near = near.any(axis=1)
        if not near.any():
            return np.empty(0, dtype=np.int64), np.empty(0, dtype=np.int64)
        x = s.nodes_m + u
        xq = s.points(u)
        facets = np.flatnonzero(np.repeat(near, len(SUBFACETS)))
        tri = x[s.facets[facets]]
        centroids = tri.mean(axis=1)
        reach = self.settings.search_mm * MM + np.linalg.norm(tri - centroids[:, None], axis=2).max(axis=1)
        n_facet = _unit(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]))
        corners = x[s.faces[:, :3]]
        n_face = _unit(np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]))
        points = s.checked_points[near[s.checked_points // len(FACE_WEIGHTS)]]
        q, f = _facing_candidates(xq, n_face, points, centroids, n_facet, reach)
        f = facets[f]
        face, other = q // len(FACE_WEIGHTS), f // len(SUBFACETS)
        keep = s.checked[face] & (~s.checked[other] | (face < other))
        q, f = q[keep], f[keep]
        x0 = s.nodes_m[s.facets[f]]
        n0 = np.cross(x0[:, 1] - x0[:, 0], x0[:, 2] - x0[:, 0])
        ahead = np.einsum("pi,pi->p", s.rest_points_m[q] - x0[:, 0], n0) > 0
        q, f = q[ahead], f[ahead]
        gap, n, inside = self._planes(u, q, f)
        own = x[s.faces[q // len(FACE_WEIGHTS), :3]]
        opposed = np.einsum("pi,pi->p", n, _unit(np.cross(own[:, 1] - own[:, 0], own[:, 2] - own[:, 0]))) < FACING_COSINE
        shallow = gap > -self.settings.search_mm * MM
        q, f = q[opposed & inside & shallow], f[opposed & inside & shallow]
        order = np.argsort(q * len(s.facets) + f)
        return q[order], f[order]

    def with_pairs(self, assignment: tuple[np.ndarray, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
        """The current assignment and `assignment` together (sorted by pair)."""
        n = len(self.surface.facets)
        keys = np.union1d(self.assignment[0] * n + self.assignment[1], assignment[0] * n + assignment[1])
        return keys // n, keys % n

    def new_pairs(self, assignment: tuple[np.ndarray, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
        """The pairs of `assignment` that the current assignment does not hold."""
        key = assignment[0] * len(self.surface.facets) + assignment[1]
        held = np.isin(key, self.assignment[0] * len(self.surface.facets) + self.assignment[1])
        return assignment[0][~held], assignment[1][~held]

    def _planes(self, u: np.ndarray, q: np.ndarray, f: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Distance (m) of points q from the planes of facets f at u, the facets' unit normals, and whether the
        points project inside the facets."""
        s = self.surface
        tri = (s.nodes_m + u)[s.facets[f]]
        e1, e2, d = tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0], s.points(u, q) - tri[:, 0]
        n = _unit(np.cross(e1, e2))
        gap = np.einsum("pi,pi->p", d, n)
        return gap, n, _inside(d - gap[:, None] * n, e1, e2)

    def pairs(self, u: np.ndarray, assignment: tuple[np.ndarray, np.ndarray] | None = None) -> ContactPairs:
        """The assigned pairs (or those given; searched at u if none is assigned) with their gaps at u (m)."""
        s = self.surface
        if assignment is None and self.assignment is None:
            self.assignment = self.search(u)
        q, f = assignment or self.assignment
        face = q // len(FACE_WEIGHTS)
        gap = self._planes(u, q, f)[0]
        coef = np.zeros((len(q), 3, 9))
        coef[:, 0, :6] = s.shape[q % len(FACE_WEIGHTS)]
        coef[:, :, 6] = -1.0
        coef[:, 1, 7] = coef[:, 2, 8] = 1.0
        return ContactPairs(q, f, gap, np.column_stack([s.faces[face], s.facets[f]]), coef)

    def active(self, u: np.ndarray) -> np.ndarray:
        """The (point, facet) pairs under pressure at u, (P, 2) sorted."""
        pairs = self.pairs(u)
        pressed = self.pressure_Pa(pairs) > 0
        return np.column_stack([pairs.point[pressed], pairs.facet[pressed]])

    def pressure_Pa(self, pairs: ContactPairs) -> np.ndarray:
        """max(0, lam - eps g) of the pairs (Pa)."""
        lam = self.multipliers.at(pairs.point * len(self.surface.facets) + pairs.facet)
        return np.maximum(0.0, lam - self.penalty_Pa_per_m * pairs.gap_m)

    def energy(self, u: np.ndarray) -> float:
        """The contact energy (J) at u."""
        pairs, eps, w = self.pairs(u), self.penalty_Pa_per_m, self.surface.weights_m2
        t = self.pressure_Pa(pairs)
        held = w[self.multipliers.keys // len(self.surface.facets)] * self.multipliers.values_Pa**2
        return float(np.sum(w[pairs.point] * t**2) - np.sum(held)) / (2 * eps)

    def forces(self, u: np.ndarray) -> np.ndarray:
        """(N, 3) nodal forces dW/du (N)."""
        f = np.zeros_like(u)
        pairs = self.pairs(u)
        t = self.pressure_Pa(pairs)
        active = t > 0
        if active.any():
            grad = self._gradient(u, pairs, active)
            np.add.at(f, pairs.nodes[active], -(self.surface.weights_m2[pairs.point[active]] * t[active])[:, None, None] * grad)
        return f

    def tangent_blocks(self, u: np.ndarray, geometric: bool = True) -> tuple[np.ndarray, np.ndarray]:
        """The assigned pairs' nodes (P, 9) and their 9 x 9 tangent blocks (P, 9, 9, 3, 3) in N/m: w eps grad g grad g
        and, if `geometric`, - w t hess g; zero for a pair without pressure, so that the tangent's sparsity pattern
        (and its factorization's ordering) holds while the assignment does.

        Without the geometric part the blocks are positive semi-definite: the tangent on which the path judges
        the part's stability (`Equilibrium.stable_factor`). On flat facets that part grows as the pressure over
        the facet's size (a facet's rotation turns its force); where a notch's flanks press together beyond
        about the shear modulus it makes the tangent indefinite: the crease, a local surface instability of
        the compressed rubber that is not a loss of the spring's load path."""
        pairs = self.pairs(u)
        t = self.pressure_Pa(pairs)
        a = t > 0
        blocks = np.zeros((len(t), 9, 9, 3, 3))
        if a.any():
            y, c = self._variables(u, pairs, a)
            _, grad_y, hess_y = plane_gap(*y)
            grad = np.einsum("pia,pic->pac", c, grad_y)
            w = self.surface.weights_m2[pairs.point[a]]
            k = (w * self.penalty_Pa_per_m)[:, None, None, None, None] * grad[:, :, None, :, None] * grad[:, None, :, None, :]
            if geometric:
                k -= (w * t[a])[:, None, None, None, None] * np.einsum("pia,pjb,pijkl->pabkl", c, c, hess_y)
            blocks[a] = k
        return pairs.nodes, blocks

    def normal_force_N(self, u: np.ndarray) -> float:
        """The sum of the pairs' normal forces at u (N): pressure times rest weight."""
        pairs = self.pairs(u)
        return float(self.surface.weights_m2[pairs.point] @ self.pressure_Pa(pairs))

    def summary(self, u: np.ndarray) -> ContactSummary:
        """The contact at u: area under pressure, its peak and where, the pairs' moment about z, the penetration."""
        pairs = self.pairs(u)
        t = self.pressure_Pa(pairs)
        a = t > 0
        if not a.any():
            return NO_CONTACT
        w = self.surface.weights_m2[pairs.point[a]]
        x = self.surface.points(u, pairs.point[a])
        force = -(w * t[a])[:, None] * self._gradient(u, pairs, a)[:, :6].sum(axis=1)  # on the checked points' faces
        moment = np.abs(x[:, 0] * force[:, 1] - x[:, 1] * force[:, 0]).sum()
        k = int(np.argmax(t[a]))
        at = tuple(float(c) for c in self.surface.rest_points_m[pairs.point[a][k]] / MM)
        area = self.surface.weights_m2[np.unique(pairs.point[a])].sum()  # a point pressed on two facets counts once
        return ContactSummary(float(area), float(t[a][k]), at, float(moment), float(max(0.0, -pairs.gap_m[a].min())))

    def augment(self, u: np.ndarray) -> None:
        """Multipliers <- the pairs' pressures at u (Uzawa's update); pairs no longer assigned carry none."""
        pairs = self.pairs(u)
        keys = pairs.point * len(self.surface.facets) + pairs.facet
        order = np.argsort(keys)
        self.multipliers = Multipliers(keys[order], self.pressure_Pa(pairs)[order])

    def closing_fraction(self, u0: np.ndarray, u1: np.ndarray) -> float:
        """How far (0 to 1) from u0 to u1, the gaps linear in between, the first of the pairs pressed at u1 closes
        its gap; 1 when no pair is pressed at u1 or none closes."""
        active = self.active(u1)
        if not len(active):
            return 1.0
        which = (active[:, 0], active[:, 1])
        g0, g1 = self.pairs(u0, which).gap_m, self.pairs(u1, which).gap_m
        closing = g1 < g0
        if not closing.any():
            return 1.0
        return float(np.clip(g0[closing] / (g0[closing] - g1[closing]), 0.0, 1.0).min())

    def gap_error_m(self, u: np.ndarray, assignment: tuple[np.ndarray, np.ndarray] | None = None) -> float:
        """The largest |gap| (m) of a pair under pressure at u, 0 without one (pairs as in `pairs`): its penetration,
        or the open gap that its multiplier still presses across (a pressure max(0, lam - eps g) > 0 at g > 0, where
        surfaces part). Frictionless contact wants gap and pressure complementary (g >= 0, p >= 0, p g = 0); the
        augmented Lagrangian has converged when this is within the tolerance."""
        pairs = self.pairs(u, assignment)
        pressed = self.pressure_Pa(pairs) > 0
        return float(np.abs(pairs.gap_m[pressed]).max()) if pressed.any() else 0.0

    def _variables(self, u: np.ndarray, pairs: ContactPairs, which: np.ndarray) -> tuple[tuple[np.ndarray, ...], np.ndarray]:
        c = pairs.coefficients[which]
        y = np.einsum("pva,pai->vpi", c, (self.surface.nodes_m + u)[pairs.nodes[which]])
        return (y[0], y[1], y[2]), c

    def _gradient(self, u: np.ndarray, pairs: ContactPairs, which: np.ndarray) -> np.ndarray:
        y, c = self._variables(u, pairs, which)
        return np.einsum("pia,pic->pac", c, plane_gap(*y)[1])


def _facing_candidates(xq: np.ndarray, n_face: np.ndarray, points: np.ndarray, centroids: np.ndarray,
                       n_facet: np.ndarray, reach: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(point, facet) pairs, among `points`, within each facet's reach of its centroid with the point's face normal
    opposed to the facet's (cosine c below `FACING_COSINE`), and some more. The search is in (position, a x normal):
    there such a pair within the reach r lies within sqrt(r^2 + 2 a^2 (1 + c)), two points of one smooth surface
    (normals alike) 2 a apart, further for a >= r. Facets are searched in classes of reach doubling from the smallest, a = the
    class's largest reach, so that a large facet does not pull in its surface's neighbours."""
    classes = np.floor(np.log2(reach / reach.min())).astype(np.int64)
    found_q, found_f = [], []
    for c in np.unique(classes):
        facets = np.flatnonzero(classes == c)
        a = float(reach[facets].max())
        tree = cKDTree(np.hstack([xq[points], -a * n_face[points // len(FACE_WEIGHTS)]]))
        near = tree.query_ball_point(np.hstack([centroids[facets], a * n_facet[facets]]), np.sqrt(reach[facets]**2 + 2 * a**2 * (1 + FACING_COSINE)))
        counts = np.fromiter(map(len, near), dtype=np.int64, count=len(near))
        if counts.sum():
            found_q.append(points[np.concatenate(near).astype(np.int64)])
            found_f.append(np.repeat(facets, counts))
    if not found_q:
        return np.empty(0, dtype=np.int64), np.empty(0, dtype=np.int64)
    return np.concatenate(found_q), np.concatenate(found_f)


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v, axis=1)[:, None]


def _inside(r: np.ndarray, e1: np.ndarray, e2: np.ndarray, tol: float = 1e-9) -> np.ndarray:
    """Whether in-plane offsets r (from a facet's first corner) lie in the facets spanned by e1, e2."""
    a11, a12, a22 = (np.einsum("pi,pi->p", a, b) for a, b in ((e1, e1), (e1, e2), (e2, e2)))
    b1, b2 = np.einsum("pi,pi->p", r, e1), np.einsum("pi,pi->p", r, e2)
    det = a11 * a22 - a12**2
    s, t = (a22 * b1 - a12 * b2) / det, (a11 * b2 - a12 * b1) / det
    return (s >= -tol) & (t >= -tol) & (s + t <= 1 + tol)
