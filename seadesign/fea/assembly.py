"""Global sparse matrices from element blocks (vectorised, chunked to bound memory).

Assembly works on node pairs: the sparsity pattern is found once from the (m * nen^2) node
pairs and the d x d blocks are summed with bincount, which is several times faster than
converting the (m * (d nen)^2) scalar triplets.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from seadesign.fea.elements import (
    ElementMesh,
    barycentric_gradients,
    lame,
    mass_reference,
    stiffness_blocks,
)

_CHUNK = 2048  # elements per vectorised block (small blocks stay in cache)


def _assemble(elements: np.ndarray, n_nodes: int, blocks: np.ndarray) -> sp.csr_matrix:
    """Sum node-pair blocks (m, nen, nen, d, d) into a CSR matrix with dofs ordered (node, component)."""
    m, nen, d = blocks.shape[0], blocks.shape[1], blocks.shape[3]
    rows = np.repeat(elements, nen, axis=1).ravel().astype(np.int64)
    cols = np.tile(elements, (1, nen)).ravel().astype(np.int64)
    keys, inv = np.unique(rows * n_nodes + cols, return_inverse=True)
    data = blocks.reshape(m * nen * nen, d * d)
    summed = np.stack([np.bincount(inv, weights=data[:, c], minlength=len(keys)) for c in range(d * d)], axis=1)
    brow, bcol = keys // n_nodes, keys % n_nodes
    indptr = np.searchsorted(brow, np.arange(n_nodes + 1))
    bsr = sp.bsr_matrix((summed.reshape(-1, d, d), bcol, indptr), shape=(d * n_nodes, d * n_nodes))
    return bsr.tocsr()


def stiffness_matrix(mesh: ElementMesh, youngs_modulus_Pa: float, poisson_ratio: float) -> sp.csr_matrix:
    """Linear-elastic stiffness matrix (N/m) of an isotropic material, full symmetric CSR."""
    lam, mu = lame(youngs_modulus_Pa, poisson_ratio)
    nen = mesh.elements.shape[1]
    blocks = np.empty((len(mesh.elements), nen, nen, 3, 3))
    for start in range(0, len(mesh.elements), _CHUNK):
        el = mesh.elements[start : start + _CHUNK]
        grads, vol = barycentric_gradients(mesh.nodes_m, el)
        blocks[start : start + len(el)] = stiffness_blocks(mesh.order, grads, vol, lam, mu)
    return _assemble(mesh.elements, len(mesh.nodes_m), blocks)


def mass_matrix(mesh: ElementMesh) -> sp.csr_matrix:
    """Scalar consistent mass matrix (m^3) used for L2 projection of nodal fields."""
    ref = mass_reference(mesh.order)
    _, vol = barycentric_gradients(mesh.nodes_m, mesh.elements)
    nen = mesh.elements.shape[1]
    blocks = (vol[:, None, None] * ref[None]).reshape(-1, nen, nen, 1, 1)
    return _assemble(mesh.elements, len(mesh.nodes_m), blocks)
