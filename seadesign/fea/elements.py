"""Lagrange tetrahedra of order 1 (4 nodes) and 2 (10 nodes, straight-sided) with vectorised
element matrices. Node order is CalculiX C3D10 / VTK quadratic tetra: vertices 0-3, then
the midpoints of edges 01, 12, 20, 03, 13, 23.

Coordinates passed here are metres; moduli are Pa.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from skfem.quadrature import get_quadrature
from skfem.refdom import RefTet

EDGES = np.array([[0, 1], [1, 2], [2, 0], [0, 3], [1, 3], [2, 3]])


@dataclass(frozen=True)
class ElementMesh:
    """Nodes (m) and element connectivity for one element order."""

    order: int
    nodes_m: np.ndarray  # (n, 3)
    elements: np.ndarray  # (m, 4) or (m, 10)
    n_vertices: int  # nodes [0, n_vertices) are the tetrahedron vertices
    edge_keys: np.ndarray  # sorted keys a * n_vertices + b (a < b) of the midside nodes, order 2


def element_mesh(points_m: np.ndarray, tets: np.ndarray, order: int) -> ElementMesh:
    """Element mesh of the given order on linear tetrahedra (points in m)."""
    nv = len(points_m)
    if order == 1:
        return ElementMesh(1, points_m, tets, nv, np.empty(0, dtype=np.int64))
    if order != 2:
        raise ValueError(f"element order must be 1 or 2, got {order}")
    e = np.sort(tets[:, EDGES], axis=2)
    keys = e[:, :, 0].astype(np.int64) * nv + e[:, :, 1]
    uniq, inv = np.unique(keys.ravel(), return_inverse=True)
    a, b = uniq // nv, uniq % nv
    nodes = np.vstack([points_m, 0.5 * (points_m[a] + points_m[b])])
    elements = np.hstack([tets, nv + inv.reshape(-1, 6)])
    return ElementMesh(2, nodes, elements, nv, uniq)


def midside_nodes(mesh: ElementMesh, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Indices of the midside nodes of edges (a, b) given by vertex indices (order 2 only)."""
    lo, hi = np.minimum(a, b), np.maximum(a, b)
    keys = lo.astype(np.int64) * mesh.n_vertices + hi
    pos = np.searchsorted(mesh.edge_keys, keys)
    if np.any(pos >= len(mesh.edge_keys)) or np.any(mesh.edge_keys[np.minimum(pos, len(mesh.edge_keys) - 1)] != keys):
        raise ValueError("edge is not part of the mesh")
    return mesh.n_vertices + pos


def shape_values(order: int, lam: np.ndarray) -> np.ndarray:
    """Shape functions (q, nen) at barycentric points lam (q, 4)."""
    if order == 1:
        return lam.copy()
    vert = lam * (2.0 * lam - 1.0)
    edge = 4.0 * lam[:, EDGES[:, 0]] * lam[:, EDGES[:, 1]]
    return np.hstack([vert, edge])


def shape_dlam(order: int, lam: np.ndarray) -> np.ndarray:
    """Derivatives (q, nen, 4) of the shape functions with respect to the barycentric coordinates."""
    q = len(lam)
    if order == 1:
        return np.broadcast_to(np.eye(4), (q, 4, 4)).copy()
    d = np.zeros((q, 10, 4))
    for i in range(4):
        d[:, i, i] = 4.0 * lam[:, i] - 1.0
    for k, (i, j) in enumerate(EDGES):
        d[:, 4 + k, i] = 4.0 * lam[:, j]
        d[:, 4 + k, j] = 4.0 * lam[:, i]
    return d


def quadrature(degree: int) -> tuple[np.ndarray, np.ndarray]:
    """Barycentric points (q, 4) and weights (q,) summing to 1 (multiply by the volume)."""
    x, w = get_quadrature(RefTet, degree)
    lam = np.vstack([1.0 - x.sum(axis=0), x]).T
    return lam, w / w.sum()


def barycentric_gradients(nodes_m: np.ndarray, tets: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Gradients (m, 4, 3) of the barycentric coordinates (1/m) and volumes (m,) in m^3."""
    p = nodes_m[tets[:, :4]]
    jac = np.stack([p[:, 1] - p[:, 0], p[:, 2] - p[:, 0], p[:, 3] - p[:, 0]], axis=2)  # columns
    inv = np.linalg.inv(jac)  # rows: grad lam_1..3
    grads = np.concatenate([-inv.sum(axis=1, keepdims=True), inv], axis=1)
    vol = np.abs(np.linalg.det(jac)) / 6.0
    return grads, vol


def lame(youngs_modulus_Pa: float, poisson_ratio: float) -> tuple[float, float]:
    """Lame parameters (lambda, mu) in Pa."""
    lam = youngs_modulus_Pa * poisson_ratio / ((1 + poisson_ratio) * (1 - 2 * poisson_ratio))
    mu = youngs_modulus_Pa / (2 * (1 + poisson_ratio))
    return lam, mu


def upper_pairs(order: int) -> tuple[np.ndarray, np.ndarray]:
    """Local node pairs (a, b) with a <= b of an element: the blocks that define a symmetric matrix."""
    return np.triu_indices(4 if order == 1 else 10)


def stiffness_blocks(
    order: int, grads: np.ndarray, vol: np.ndarray, lam: float, mu: float
) -> np.ndarray:
    """Element stiffness blocks K_ab (P, m, 3, 3) in N/m for the upper_pairs (a, b), pair-major.

    Shape-function gradients are combinations of the barycentric gradients G_k, so
    K_ab = sum_kl C[ab, kl] E_kl with C[ab, kl] = int dN_a/dlam_k dN_b/dlam_l (exact with the
    degree-2(order-1) rule on straight-sided elements) and the per-element 3x3 matrices
    E_kl = vol (lam G_k G_l^T + mu G_l G_k^T + mu (G_k . G_l) I): one matrix product per chunk.
    """
    qlam, qw = quadrature(2 * (order - 1))
    dlam = shape_dlam(order, qlam)  # (q, nen, 4)
    ia, ib = upper_pairs(order)
    c = np.einsum("q,qak,qbl->abkl", qw, dlam, dlam)[ia, ib].reshape(len(ia), 16)
    outer = grads[:, :, None, :, None] * grads[:, None, :, None, :]  # (m, k, l, i, j) = G_ki G_lj
    e = lam * outer + mu * outer.transpose(0, 2, 1, 3, 4)  # mu G_kj G_li = mu (G_l G_k^T)_ij
    dots = np.einsum("mki,mli->mkl", grads, grads)
    e[..., [0, 1, 2], [0, 1, 2]] += mu * dots[..., None]
    e *= vol[:, None, None, None, None]
    e = e.transpose(1, 2, 0, 3, 4).reshape(16, -1)  # (kl, m * 9)
    return (c @ e).reshape(len(ia), len(vol), 3, 3)


def mass_reference(order: int) -> np.ndarray:
    """Scalar mass matrix (nen, nen) of a tetrahedron of unit volume."""
    qlam, qw = quadrature(2 * order)
    n = shape_values(order, qlam)
    return np.einsum("q,qa,qb->ab", qw, n, n)


def linear_projection_reference(order: int) -> np.ndarray:
    """Matrix (nen, 4) of int N_a lam_k over a tetrahedron of unit volume."""
    qlam, qw = quadrature(order + 1)
    n = shape_values(order, qlam)
    return np.einsum("q,qa,qk->ak", qw, n, qlam)
