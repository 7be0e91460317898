"""Rigid (RBE2-like) couplings by master-slave condensation of the assembled blocks.

A coupled node moves with its reference point: u = t + w x (x - x_ref), with t (m) and w (rad)
the reference point's six degrees of freedom. Held nodes get no row (u = 0).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from seadesign.errors import SolverError
from seadesign.fea.assembly import UpperBlocks


def cross_matrices(arms_m: np.ndarray) -> np.ndarray:
    """(n, 3, 3) matrices R with R w = w x arm."""
    x, y, z = arms_m.T
    o = np.zeros_like(x)
    return np.stack([np.stack([o, z, -y], 1), np.stack([-z, o, x], 1), np.stack([y, -x, o], 1)], 1)


def _sum_rows(inv: np.ndarray, values: np.ndarray, n: int) -> np.ndarray:
    out = np.zeros((n,) + values.shape[1:])
    np.add.at(out, inv, values)
    return out


@dataclass(frozen=True)
class RigidCoupling:
    """Numbering for one coupled and one held node set. Before condensation free nodes take
    block rows 0..n_free-1 and coupled nodes the rows after; held nodes none. After it, block
    rows n_free and n_free + 1 are the reference point's translation t and rotation w."""

    node_index: np.ndarray  # (N,) block row of each node, -1 for held nodes
    n_free: int
    coupled: np.ndarray  # coupled node ids, in row order
    arms_m: np.ndarray  # (nc, 3) coupled node position minus the reference point

    @property
    def n_rows(self) -> int:
        """Block rows before condensation."""
        return self.n_free + len(self.coupled)

    @property
    def ref_dofs(self) -> np.ndarray:
        """Indices in the condensed unknowns of (tx, ty, tz, wx, wy, wz)."""
        return 3 * self.n_free + np.arange(6)

    def condense(self, k: UpperBlocks) -> UpperBlocks:
        """T^T K T for u = T q, on 3x3 upper blocks: free-free blocks stay, free-coupled blocks
        fold into the free rows' t and w columns, coupled-coupled blocks into one 6x6."""
        nf, r, c, v = self.n_free, k.rows, k.cols, k.values
        ff, cc = c < nf, r >= nf
        fc = ~ff & ~cc
        rot = cross_matrices(self.arms_m)
        rows_fc, inv = np.unique(r[fc], return_inverse=True)
        to_t = _sum_rows(inv, v[fc], len(rows_fc))
        to_w = _sum_rows(inv, v[fc] @ rot[c[fc] - nf], len(rows_fc))
        a, b = r[cc] - nf, c[cc] - nf
        eye = np.broadcast_to(np.eye(3), (len(a), 3, 3))
        ca, cb = np.concatenate([eye, rot[a]], axis=2), np.concatenate([eye, rot[b]], axis=2)
        s = ca.transpose(0, 2, 1) @ v[cc] @ cb  # (k, 6, 6); a lower twin exists where a != b
        big = s.sum(axis=0) + s[a != b].transpose(0, 2, 1).sum(axis=0)
        rows = np.concatenate([r[ff], rows_fc, rows_fc, [nf, nf, nf + 1]])
        cols = np.concatenate([c[ff], np.full(len(rows_fc), nf), np.full(len(rows_fc), nf + 1), [nf, nf + 1, nf + 1]])
        vals = np.concatenate([v[ff], to_t, to_w, [big[:3, :3], big[:3, 3:], big[3:, 3:]]])
        order = np.lexsort((cols, rows))
        return UpperBlocks(rows[order], cols[order], vals[order], nf + 2)

    def displacements(self, q: np.ndarray) -> np.ndarray:
        """(N, 3) nodal displacements from the condensed unknowns q."""
        u = np.zeros((len(self.node_index), 3))
        free = np.flatnonzero((self.node_index >= 0) & (self.node_index < self.n_free))
        u[free] = q[: 3 * self.n_free].reshape(-1, 3)
        t, w = q[self.ref_dofs[:3]], q[self.ref_dofs[3:]]
        u[self.coupled] = t + cross_matrices(self.arms_m) @ w
        return u


def couple(nodes_m: np.ndarray, coupled: np.ndarray, held: np.ndarray, ref_m: np.ndarray) -> RigidCoupling:
    """Numbering for one rigidly coupled node set (free reference point) and one held node set."""
    if len(coupled) == 0 or len(held) == 0:
        raise SolverError(
            f"rigid coupling needs both surfaces: {len(coupled)} coupled and {len(held)} held nodes found; "
            "check that the Interfaces radii match the mesh"
        )
    if np.intersect1d(coupled, held).size:
        raise SolverError("the coupled and the held surfaces share nodes; they must be separate interfaces")
    kind = np.zeros(len(nodes_m), dtype=np.int8)
    kind[coupled], kind[held] = 1, 2
    free = np.flatnonzero(kind == 0)
    coupled = np.flatnonzero(kind == 1)
    index = np.full(len(nodes_m), -1, dtype=np.int64)
    index[free] = np.arange(len(free))
    index[coupled] = len(free) + np.arange(len(coupled))
    return RigidCoupling(index, len(free), coupled, nodes_m[coupled] - np.asarray(ref_m, dtype=float))
