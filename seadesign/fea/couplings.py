"""Rigid (RBE2-like) couplings by master-slave elimination.

A coupled node moves with its reference point: u = t + w x (x - x_ref), with t (m) and w (rad)
the reference point's six degrees of freedom. Held nodes are removed (u = 0).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from seadesign.errors import SolverError


def rigid_rows(nodes_m: np.ndarray, ref_m: np.ndarray) -> np.ndarray:
    """(3 n, 6) map from reference motion (tx, ty, tz, wx, wy, wz) to nodal displacements."""
    d = nodes_m - ref_m
    n = len(d)
    c = np.zeros((n, 3, 6))
    c[:, 0, 0] = c[:, 1, 1] = c[:, 2, 2] = 1.0
    c[:, 0, 4], c[:, 0, 5] = d[:, 2], -d[:, 1]
    c[:, 1, 3], c[:, 1, 5] = -d[:, 2], d[:, 0]
    c[:, 2, 3], c[:, 2, 4] = d[:, 1], -d[:, 0]
    return c.reshape(3 * n, 6)


@dataclass(frozen=True)
class Coupling:
    """u = T q: q holds the free dofs, then the six dofs of the coupled reference point."""

    transform: sp.csr_matrix  # (3 N, n_free + 6)
    n_free: int
    ref_m: np.ndarray  # (3,)

    @property
    def ref_dofs(self) -> np.ndarray:
        """Indices in q of (tx, ty, tz, wx, wy, wz) of the reference point."""
        return self.n_free + np.arange(6)


def couple(nodes_m: np.ndarray, coupled: np.ndarray, held: np.ndarray, ref_m: np.ndarray) -> Coupling:
    """Transform for one rigidly coupled node set (free reference point) and one held node set."""
    if len(coupled) == 0 or len(held) == 0:
        raise SolverError(
            f"rigid coupling needs both surfaces: {len(coupled)} coupled and {len(held)} held nodes found; "
            "check that the Interfaces radii match the mesh"
        )
    if np.intersect1d(coupled, held).size:
        raise SolverError("the coupled and the held surfaces share nodes; they must be separate interfaces")
    n_nodes = len(nodes_m)
    kind = np.zeros(n_nodes, dtype=np.int8)
    kind[coupled], kind[held] = 1, 2
    free_nodes = np.flatnonzero(kind == 0)
    free_dofs = (3 * free_nodes[:, None] + np.arange(3)).ravel()
    n_free = len(free_dofs)
    rows = [free_dofs]
    cols = [np.arange(n_free)]
    vals = [np.ones(n_free)]
    c = rigid_rows(nodes_m[coupled], ref_m)
    cdofs = (3 * coupled[:, None] + np.arange(3)).ravel()
    nz = c != 0.0
    r_idx, c_idx = np.nonzero(nz)
    rows.append(cdofs[r_idx])
    cols.append(n_free + c_idx)
    vals.append(c[nz])
    t = sp.csr_matrix(
        (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(3 * n_nodes, n_free + 6)
    )
    return Coupling(transform=t, n_free=n_free, ref_m=np.asarray(ref_m, dtype=float))
