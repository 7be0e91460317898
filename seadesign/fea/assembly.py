"""Global sparse matrices as the upper (block) triangle of a symmetric matrix.

Assembly works on node pairs: every element contributes its nen(nen+1)/2 upper pair blocks,
each mapped to global block rows (transposed where the global order flips, dropped where a
node has no row, e.g. a held node), and equal (row, col) entries are summed (`fea.kernels`). The
map from element blocks to global entries depends only on the mesh and the numbering: a
`PairPattern` keeps it for matrices assembled many times (the finite-strain tangent).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from seadesign.fea.elements import (
    ElementMesh,
    barycentric_gradients,
    lame,
    mass_reference,
    stiffness_blocks,
    upper_pairs,
)
from seadesign.fea.kernels import sum_blocks

_CHUNK = 8192  # elements per vectorised block


@dataclass(frozen=True)
class UpperBlocks:
    """Entries (rows[i], cols[i]) with cols >= rows, sorted by row then column, of a symmetric
    matrix with n block rows; values (k, d, d), diagonal blocks stored in full."""

    rows: np.ndarray
    cols: np.ndarray
    values: np.ndarray
    n: int

    def matrix(self) -> sp.csr_matrix | sp.bsr_matrix:
        """Scalar CSR (d = 1) or BSR (d > 1) upper triangle, as the factorization takes it."""
        d = self.values.shape[1]
        indptr = np.searchsorted(self.rows, np.arange(self.n + 1))
        if d == 1:
            return sp.csr_matrix((self.values[:, 0, 0], self.cols, indptr), shape=(self.n, self.n))
        return sp.bsr_matrix((self.values, self.cols, indptr), shape=(d * self.n, d * self.n))


def add_pair_blocks(upper: UpperBlocks, node_index: np.ndarray, nodes: np.ndarray, blocks: np.ndarray) -> UpperBlocks:
    """`upper` plus the blocks (P, q, q, d, d) of the dense q x q node groups `nodes` (P, q) (a contact pair's
    coupling), mapped by node_index to block rows (-1: dropped); new entries join the sparsity pattern. The entries
    are merged into `upper`'s sorted ones, never sorted again: the pairs add few entries to many."""
    r = node_index[nodes][:, :, None].repeat(nodes.shape[1], axis=2)
    c = np.swapaxes(r, 1, 2)
    keep = (r >= 0) & (c >= 0) & (r <= c)
    keys = r[keep].astype(np.int64) * upper.n + c[keep]
    held = upper.rows.astype(np.int64) * upper.n + upper.cols
    added = np.unique(keys)
    at = np.searchsorted(held, added)
    added = added[(at == len(held)) | (held[np.minimum(at, len(held) - 1)] != added)]
    at = np.searchsorted(held, added)
    merged = np.insert(held, at, added)
    values = np.insert(upper.values, at, 0.0, axis=0)
    np.add.at(values, np.searchsorted(merged, keys), blocks[keep])
    return UpperBlocks(merged // upper.n, merged % upper.n, values, upper.n)


@dataclass(frozen=True)
class PairPattern:
    """Where the element pair blocks (P, m, d, d) of one mesh and numbering land in the global upper
    triangle, computed once: the global entry each block adds to (-1: dropped, a node without a row),
    transposed where the global order of its pair flips."""

    rows: np.ndarray
    cols: np.ndarray
    n: int
    target: np.ndarray  # (P * m,) global entry of each pair block, -1: dropped
    flip: np.ndarray  # (P * m,) the block is added transposed

    @classmethod
    def of(cls, elements: np.ndarray, order: int, node_index: np.ndarray, n: int) -> "PairPattern":
        """node_index maps mesh nodes to block rows (-1: no row, e.g. a held node)."""
        ia, ib = upper_pairs(order)
        r = node_index[elements[:, ia].T].ravel()
        c = node_index[elements[:, ib].T].ravel()
        kept = (r >= 0) & (c >= 0)
        keys, inv = np.unique(np.minimum(r[kept], c[kept]).astype(np.int64) * n + np.maximum(r[kept], c[kept]),
                              return_inverse=True)
        target = np.full(len(r), -1, dtype=np.int64)
        target[kept] = inv
        return cls(keys // n, keys % n, n, target, r > c)

    def sum(self, blocks: np.ndarray) -> UpperBlocks:
        """The global upper blocks of element pair blocks (P, m, d, d) over upper_pairs(order)."""
        d = blocks.shape[-1]
        return UpperBlocks(self.rows, self.cols, sum_blocks(blocks.reshape(-1, d, d), self.target, self.flip,
                                                            len(self.rows)), self.n)


def sum_pair_blocks(
    elements: np.ndarray, order: int, blocks: np.ndarray, node_index: np.ndarray, n: int
) -> UpperBlocks:
    """Sum element pair blocks (P, m, d, d) over upper_pairs(order); node_index maps mesh nodes to block
    rows (-1: no row). For one numbering used many times, keep its `PairPattern`."""
    return PairPattern.of(elements, order, node_index, n).sum(blocks)


def _stiffness_pair_blocks(mesh: ElementMesh, elements: np.ndarray, lam: float, mu: float) -> np.ndarray:
    nen = elements.shape[1]
    blocks = np.empty((nen * (nen + 1) // 2, len(elements), 3, 3))
    for start in range(0, len(elements), _CHUNK):
        el = elements[start : start + _CHUNK]
        grads, vol = barycentric_gradients(mesh.nodes_m, el)
        blocks[:, start : start + len(el)] = stiffness_blocks(mesh.order, grads, vol, lam, mu)
    return blocks


def stiffness_upper(
    mesh: ElementMesh, youngs_modulus_Pa: float, poisson_ratio: float,
    node_index: np.ndarray | None = None, n: int | None = None,
) -> UpperBlocks:
    """Linear-elastic stiffness (N/m) of an isotropic material in 3x3 node blocks; node_index
    and n as in sum_pair_blocks (default: every node its own row)."""
    if node_index is None:
        node_index, n = np.arange(len(mesh.nodes_m)), len(mesh.nodes_m)
    blocks = _stiffness_pair_blocks(mesh, mesh.elements, *lame(youngs_modulus_Pa, poisson_ratio))
    return sum_pair_blocks(mesh.elements, mesh.order, blocks, node_index, n)


def mass_upper(mesh: ElementMesh) -> UpperBlocks:
    """Scalar consistent mass matrix (m^3) used for L2 projection of nodal fields."""
    ia, ib = upper_pairs(mesh.order)
    _, vol = barycentric_gradients(mesh.nodes_m, mesh.elements)
    blocks = (mass_reference(mesh.order)[ia, ib][:, None] * vol[None]).reshape(len(ia), len(vol), 1, 1)
    n = len(mesh.nodes_m)
    return sum_pair_blocks(mesh.elements, mesh.order, blocks, np.arange(n), n)


def nodal_forces(
    mesh: ElementMesh, u_m: np.ndarray, youngs_modulus_Pa: float, poisson_ratio: float, nodes: np.ndarray
) -> np.ndarray:
    """(N, 3) internal forces K u in N on the given nodes (zero elsewhere), from the elements
    that touch them."""
    touching = np.isin(mesh.elements, nodes).any(axis=1)
    el = mesh.elements[touching]
    k = _stiffness_pair_blocks(mesh, el, *lame(youngs_modulus_Pa, poisson_ratio))
    ia, ib = upper_pairs(mesh.order)
    na, nb = el[:, ia].T, el[:, ib].T
    fa = np.einsum("pmij,pmj->pmi", k, u_m[nb])  # K_ab u_b at a
    fb = np.einsum("pmij,pmi->pmj", k, u_m[na])  # K_ab^T u_a at b, for a != b
    off = ia != ib
    idx = np.concatenate([na.ravel(), nb[off].ravel()])
    val = np.concatenate([fa.reshape(-1, 3), fb[off].reshape(-1, 3)])
    f = np.stack([np.bincount(idx, weights=val[:, i], minlength=len(u_m)) for i in range(3)], axis=1)
    out = np.zeros_like(f)
    out[nodes] = f[nodes]
    return out
