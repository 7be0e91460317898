"""Sparse symmetric positive-definite factorization: one factorization, many right-hand sides."""

from __future__ import annotations

import os

import numpy as np
import scipy.sparse as sp

from seadesign.errors import SolverError


def _pardiso_solver(mtype: int):
    """A PyPardisoSolver; the MKL runtime path found by the first one is reused, because
    pypardiso otherwise searches the whole environment tree (seconds) for every instance."""
    import pypardiso

    solver = pypardiso.PyPardisoSolver(mtype=mtype)
    name = getattr(solver.libmkl, "_name", None)
    if name and "PYPARDISO_MKL_RT" not in os.environ:
        os.environ["PYPARDISO_MKL_RT"] = name
    return solver


class SPDFactorization:
    """Factorization of a symmetric positive-definite matrix by MKL PARDISO (via pypardiso,
    Cholesky, mtype 2) or SciPy's SuperLU when backend="scipy"."""

    def __init__(self, a: sp.spmatrix, backend: str = "pardiso") -> None:
        a = sp.csr_matrix(a)
        self.n = a.shape[0]
        self.backend = backend
        self._solver = None
        if backend == "pardiso":
            self._upper = sp.triu(a, format="csr")
            self._upper.sort_indices()
            self._solver = _pardiso_solver(mtype=2)
            try:
                self._solver.factorize(self._upper)
            except Exception as exc:  # pardiso reports non-SPD and memory errors as exceptions
                raise SolverError(f"PARDISO factorization failed: {exc}; the structure may be under-constrained") from None
        elif backend == "scipy":
            import scipy.sparse.linalg as sla

            try:
                self._lu = sla.splu(a.tocsc(), permc_spec="MMD_AT_PLUS_A")
            except RuntimeError as exc:
                raise SolverError(f"SuperLU factorization failed: {exc}; the structure may be under-constrained") from None
        else:
            raise SolverError(f"unknown linear solver backend {backend!r}; use 'pardiso' or 'scipy'")

    def close(self) -> None:
        """Release PARDISO's factorization memory (MKL keeps it outside Python's heap, and
        pypardiso does not free it when the solver object is collected)."""
        if self.backend == "pardiso" and self._solver is not None:
            self._solver.free_memory(everything=True)
            self._solver = None

    def __del__(self) -> None:
        self.close()

    def solve(self, b: np.ndarray) -> np.ndarray:
        """Solution of A x = b for one (n,) or several (n, r) right-hand sides."""
        b = np.ascontiguousarray(b, dtype=np.float64)
        if self.backend == "pardiso":
            x = self._solver.solve(self._upper, b)
        else:
            x = self._lu.solve(b)
        if not np.all(np.isfinite(x)):
            raise SolverError("the linear solve returned non-finite values; the structure may be under-constrained")
        return x
