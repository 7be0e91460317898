"""scikit-fem's vector P1/P2 basis on our tetrahedra, and the map from its degrees of freedom to ours."""

from __future__ import annotations

import numpy as np
from skfem import Basis, ElementTetP1, ElementTetP2, ElementVector, MeshTet

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
