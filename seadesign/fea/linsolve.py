"""Sparse symmetric positive-definite factorization: one factorization, many right-hand sides.
Matrices arrive as their upper triangle (scalar CSR or block BSR with full diagonal blocks)."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from seadesign.errors import SolverError


def full_from_upper(upper: sp.spmatrix) -> sp.csr_matrix:
    """The symmetric matrix whose upper triangle (scalar or block) is given."""
    u = sp.triu(sp.csr_matrix(upper), format="csr")
    return (u + sp.triu(u, 1).T).tocsr()


class SPDFactorization:
    """Factorization by MKL PARDISO (Cholesky) or, with backend="scipy", SciPy's SuperLU."""

    def __init__(self, upper: sp.spmatrix, backend: str = "pardiso") -> None:
        self.n = upper.shape[0]
        self.backend = backend
        if backend == "pardiso":
            from seadesign.fea.pardiso import Pardiso

            self._solver = Pardiso(upper)
        elif backend == "scipy":
            import scipy.sparse.linalg as sla

            try:
                self._solver = sla.splu(full_from_upper(upper).tocsc(), permc_spec="MMD_AT_PLUS_A")
            except RuntimeError as exc:
                raise SolverError(f"SuperLU factorization failed: {exc}; the structure may be under-constrained") from None
        else:
            raise SolverError(f"unknown linear solver backend {backend!r}; use 'pardiso' or 'scipy'")

    def close(self) -> None:
        """Release the factorization's memory now."""
        if self.backend == "pardiso":
            self._solver.close()

    def solve(self, b: np.ndarray) -> np.ndarray:
        """Solution of A x = b for one (n,) or several (n, r) right-hand sides."""
        x = self._solver.solve(np.ascontiguousarray(b, dtype=np.float64))
        if not np.all(np.isfinite(x)):
            raise SolverError("the linear solve returned non-finite values; the structure may be under-constrained")
        return x
