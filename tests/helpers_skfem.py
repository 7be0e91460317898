"""scikit-fem's vector P1/P2 basis on our tetrahedra, the map from its degrees of freedom to ours, and
CalculiX's neo-Hookean law written apart from seadesign.fea.hyperelastic as a scikit-fem residual and
tangent (the tests' reference; benchmarks/fea.py times scikit-fem's assembly of it against ours)."""

from __future__ import annotations

import numpy as np
from skfem import Basis, BilinearForm, ElementTetP1, ElementTetP2, ElementVector, LinearForm, MeshTet
from skfem.helpers import grad

from seadesign.fea.elements import midside_nodes


def skfem_permutation(points, tets, emesh, intorder=None):
    """Our dof index of each scikit-fem dof (vector P1/P2, 3 components per node)."""
    mesh = MeshTet(points.T.copy(), tets.T.copy())
    element = ElementVector(ElementTetP2() if emesh.order == 2 else ElementTetP1())
    basis = Basis(mesh, element) if intorder is None else Basis(mesh, element, intorder=intorder)
    ours = np.empty(basis.N, dtype=np.int64)
    for c in range(3):
        ours[basis.nodal_dofs[c]] = 3 * np.arange(mesh.nvertices) + c
        if emesh.order == 2:
            mid = midside_nodes(emesh, mesh.edges[0], mesh.edges[1])
            ours[basis.edge_dofs[c]] = 3 * mid + c
    return basis, ours


def _last(a):  # (3, 3, e, q) -> (e, q, 3, 3)
    return np.moveaxis(a, (0, 1), (-2, -1))


def _first(a):
    return np.moveaxis(a, (-2, -1), (0, 1))


def _neo_hooke_parts(F, c10, d1):
    Fl = _last(F)
    J = np.linalg.det(Fl)
    H = np.swapaxes(np.linalg.inv(Fl), -1, -2)
    I1 = np.einsum("...ij,...ij->...", Fl, Fl)
    return Fl, J, H, I1


def _P(F, c10, d1):
    Fl, J, H, I1 = _neo_hooke_parts(F, c10, d1)
    j23 = J ** (-2 / 3)
    P = c10 * j23[..., None, None] * (2 * Fl - (2 / 3) * I1[..., None, None] * H) \
        + (2 / d1) * ((J - 1) * J)[..., None, None] * H
    return _first(P)


def _dP(F, G, c10, d1):
    """Directional derivative of P at F along G (both (3, 3, e, q))."""
    Fl, J, H, I1 = _neo_hooke_parts(F, c10, d1)
    Gl = _last(G)
    hg = np.einsum("...ij,...ij->...", H, Gl)  # tr(F^-1 G)
    dI1 = 2 * np.einsum("...ij,...ij->...", Fl, Gl)
    dH = -H @ np.swapaxes(Gl, -1, -2) @ H
    j23 = J ** (-2 / 3)
    e = (..., None, None)
    iso = c10 * (-(2 / 3) * (j23 * hg)[e] * (2 * Fl - (2 / 3) * I1[e] * H)
                 + j23[e] * (2 * Gl - (2 / 3) * dI1[e] * H - (2 / 3) * I1[e] * dH))
    vol = (2 / d1) * (((2 * J - 1) * J * hg)[e] * H + ((J - 1) * J)[e] * dH)
    return _first(iso + vol)


def neo_hooke_forms(c10_Pa: float, d1_per_Pa: float) -> tuple[LinearForm, BilinearForm]:
    """The residual int P : grad v and the tangent int dP[grad du] : grad v of C10 (I1bar - 3) + (J - 1)^2 / D1
    at the displacement field passed as `prev`."""

    @LinearForm
    def residual(v, w):
        return np.einsum("ij...,ij...->...", _P(grad(w["prev"]) + np.eye(3)[:, :, None, None], c10_Pa, d1_per_Pa), grad(v))

    @BilinearForm
    def stiffness(du, v, w):
        F = grad(w["prev"]) + np.eye(3)[:, :, None, None]
        return np.einsum("ij...,ij...->...", _dP(F, grad(du), c10_Pa, d1_per_Pa), grad(v))

    return residual, stiffness
