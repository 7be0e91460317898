"""The geometry contact is computed on: a quadratic boundary face split into flat facets, its Gauss points and
shape functions, and the signed distance of a point from a facet's plane with its exact first and second
derivatives (`plane_gap`, checked against automatic differentiation in `tests/test_fea_contact.py`). SI units.
"""

from __future__ import annotations

import numpy as np

# The quadratic boundary face (corners 0-2, then the midsides of edges 01, 12, 20) split into four flat facets
SUBFACETS = np.array([[0, 3, 5], [3, 1, 4], [5, 4, 2], [3, 4, 5]])
# Dunavant's 6-point rule on the triangle (degree 4): barycentric points and weights summing to 1
_A, _B = 0.445948490915965, 0.091576213509771
FACE_POINTS = np.array([[_A, _A, 1 - 2 * _A], [_A, 1 - 2 * _A, _A], [1 - 2 * _A, _A, _A],
                        [_B, _B, 1 - 2 * _B], [_B, 1 - 2 * _B, _B], [1 - 2 * _B, _B, _B]])
FACE_WEIGHTS = np.array([0.223381589678011] * 3 + [0.109951743655322] * 3)


def face_shape_values(lam: np.ndarray) -> np.ndarray:
    """Quadratic triangle shape functions (q, 6) at barycentric points lam (q, 3): corners, then midsides 01, 12, 20."""
    l0, l1, l2 = lam.T
    return np.column_stack([l0 * (2 * l0 - 1), l1 * (2 * l1 - 1), l2 * (2 * l2 - 1), 4 * l0 * l1, 4 * l1 * l2, 4 * l2 * l0])


def _cross_matrix(v: np.ndarray) -> np.ndarray:
    """[v]x (..., 3, 3): [v]x w = v x w."""
    z = np.zeros(v.shape[:-1])
    return np.stack([np.stack([z, -v[..., 2], v[..., 1]], -1), np.stack([v[..., 2], z, -v[..., 0]], -1),
                     np.stack([-v[..., 1], v[..., 0], z], -1)], -2)


def plane_gap(d: np.ndarray, e1: np.ndarray, e2: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The signed distance g = d . n of points from the planes of facets (P,), n = e1 x e2 / |e1 x e2|, with d the
    point minus the facet's first corner and e1, e2 its edges from there (P, 3, m); and its gradient (P, 3, 3) and
    Hessian (P, 3, 3, 3, 3) in the variables (d, e1, e2): [variable, component] and
    [variable, variable, component, component]."""
    m = np.cross(e1, e2)
    a = np.linalg.norm(m, axis=1)
    n = m / a[:, None]
    g = np.einsum("pi,pi->p", d, n)
    p = (d - g[:, None] * n) / a[:, None]  # dg/dm
    grad = np.stack([n, np.cross(e2, p), np.cross(p, e1)], axis=1)
    proj = np.eye(3) - n[:, :, None] * n[:, None, :]
    h_mm = -(n[:, :, None] * p[:, None, :] + p[:, :, None] * n[:, None, :]) / a[:, None, None] \
        - g[:, None, None] * proj / (a**2)[:, None, None]
    j1, j2 = -_cross_matrix(e2), _cross_matrix(e1)  # dm/de1, dm/de2
    h_dm = proj / a[:, None, None]
    hess = np.zeros((len(g), 3, 3, 3, 3))
    hess[:, 0, 1], hess[:, 0, 2] = h_dm @ j1, h_dm @ j2
    hess[:, 1, 0], hess[:, 2, 0] = np.swapaxes(hess[:, 0, 1], 1, 2), np.swapaxes(hess[:, 0, 2], 1, 2)
    hess[:, 1, 1] = np.swapaxes(j1, 1, 2) @ h_mm @ j1
    hess[:, 2, 2] = np.swapaxes(j2, 1, 2) @ h_mm @ j2
    hess[:, 1, 2] = np.swapaxes(j1, 1, 2) @ h_mm @ j2 - _cross_matrix(p)
    hess[:, 2, 1] = np.swapaxes(hess[:, 1, 2], 1, 2)
    return g, grad, hess
