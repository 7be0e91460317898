"""Sparse symmetric positive-definite factorization: one factorization, many right-hand sides.
Matrices arrive as their upper triangle (scalar CSR or block BSR with full diagonal blocks).

Mixed precision (`precision="mixed"`, PARDISO only): the factors in single precision precondition SciPy's conjugate
gradients on the matrix in double precision, to a residual of MIXED_RTOL of the load: on the default study's result
meshes in about five iterations, with less memory and time than double-precision factors and their solution to
1e-11 (docs/validation/linear-fea.md#mixed-precision, benchmarks/linear_solve.py). A matrix
too ill-conditioned for single precision (its single-precision factorization meets a non-positive pivot, or the
iterations do not converge) is factored in double precision instead: the answer never depends on the precision.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from seadesign.errors import NotPositiveDefinite, SolverError

PRECISIONS = ("double", "mixed")
MIXED_RTOL = 1e-12  # residual of a mixed-precision solve, relative to the load's norm
MIXED_MAXITER = 30  # conjugate-gradient iterations a mixed-precision solve may take before double precision (it takes
# about five)


def full_from_upper(upper: sp.spmatrix) -> sp.csr_matrix:
    """The symmetric matrix whose upper triangle (scalar or block) is given."""
    u = sp.triu(sp.csr_matrix(upper), format="csr")
    return (u + sp.triu(u, 1).T).tocsr()


class SPDFactorization:
    """Factorization by MKL PARDISO (Cholesky) or, with backend="scipy", SciPy's SuperLU; `precision` "mixed":
    PARDISO's factors in single precision, refined by conjugate gradients in double (see the module)."""

    def __init__(self, upper: sp.spmatrix, backend: str = "pardiso", precision: str = "double") -> None:
        self.n = upper.shape[0]
        self.backend = backend
        if precision not in PRECISIONS or (precision == "mixed" and backend != "pardiso"):
            raise SolverError(f"precision {precision!r} with backend {backend!r}: use 'double', or 'mixed' with "
                              "'pardiso'")
        self._mixed = _SymmetricUpper(upper) if precision == "mixed" else None
        self.iterations = 0  # conjugate-gradient iterations of the mixed-precision solves so far
        if backend == "pardiso":
            from seadesign.fea.pardiso import Pardiso

            try:
                self._solver = Pardiso(upper, single=self._mixed is not None)
            except NotPositiveDefinite:  # closed by PARDISO's error
                if self._mixed is None:
                    raise
                self._mixed, self._solver = None, Pardiso(upper)
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
        b = np.ascontiguousarray(b, dtype=np.float64)
        x = self._refined(b) if self._mixed is not None else self._solver.solve(b)
        if not np.all(np.isfinite(x)):
            raise SolverError("the linear solve returned non-finite values; the structure may be under-constrained")
        return x

    def _refined(self, b: np.ndarray) -> np.ndarray:
        """Conjugate gradients on the double-precision matrix, preconditioned by the single-precision factors (the
        double-precision factors' solution where they do not converge)."""
        import scipy.sparse.linalg as sla

        a = sla.LinearOperator((self.n, self.n), self._mixed.matvec)
        m = sla.LinearOperator((self.n, self.n), self._solver.solve)
        columns = []
        for column in b.reshape(self.n, -1).T:
            x, info = sla.cg(a, column, rtol=MIXED_RTOL, atol=0.0, maxiter=MIXED_MAXITER, M=m, callback=self._count)
            if info != 0:  # too ill-conditioned for single-precision factors
                from seadesign.fea.pardiso import Pardiso

                upper, self._mixed = self._mixed.upper, None
                self.close()
                self._solver = Pardiso(upper)
                return self._solver.solve(b)
            columns.append(x)
        return np.stack(columns, axis=1).reshape(b.shape)

    def _count(self, _x: np.ndarray) -> None:
        self.iterations += 1


class _SymmetricUpper:
    """The product with a symmetric matrix stored as its upper (block) triangle with full diagonal blocks:
    U x + U^T x - D x, D the diagonal blocks (U^T formed once)."""

    def __init__(self, upper: sp.spmatrix) -> None:
        self.upper = upper
        self.lower = upper.T
        d = upper.blocksize[0] if upper.format == "bsr" else 1
        rows = np.repeat(np.arange(upper.shape[0] // d), np.diff(upper.indptr))
        diagonal = rows == upper.indices
        blocks = upper.data[diagonal] if d > 1 else upper.data[diagonal][:, None, None]
        ids = np.arange(len(blocks))
        self.diagonal = sp.bsr_matrix((blocks, ids, np.append(ids, len(ids))), shape=upper.shape)

    def matvec(self, x: np.ndarray) -> np.ndarray:
        x = np.ravel(x)
        return self.upper @ x + self.lower @ x - self.diagonal @ x
