"""A small ctypes binding to MKL PARDISO (libmkl_rt from the `mkl` wheel) for symmetric
positive-definite matrices stored as their upper triangle, in CSR or in 3x3-block BSR.

MKL runs in conditional-numerical-reproducibility mode (MKL_CBWR=AUTO unless the environment sets
MKL_CBWR): with more than one thread, PARDISO's factorization otherwise differs in the last digits from
run to run (a large-deflection path by 1e-13 Nm), and the explorer, which fits its surrogates on those
digits, took another route on every run. MKL promises that only for a fixed number of threads, so it is
also kept from choosing fewer threads when the machine is busy (MKL_DYNAMIC=FALSE unless the environment
sets MKL_DYNAMIC; Intel's reproducibility conditions): a path through a creasing notch amplifies the last
digits. On the matrices measured (to 81,000 unknowns in 3x3 blocks) 1 and 2 threads gave the same solutions to
the last digit; NumPy's BLAS does not (`fea.blas`).

Block storage matters: PARDISO then orders the node graph, nine times smaller than the
scalar one (measured in docs/validation/linear-fea.md).
"""

from __future__ import annotations

import ctypes
import glob
import os
import sys
from functools import cache

import numpy as np
import scipy.sparse as sp

from seadesign.errors import NotPositiveDefinite, SolverError

_SPD = 2  # PARDISO mtype: real symmetric positive definite
_SYMMETRIC = -2  # real symmetric indefinite (Bunch-Kaufman), which reports the inertia
_ERRORS = {
    -2: "not enough memory",
    -3: "reordering failed",
    -4: "zero or negative pivot: the matrix is not positive definite (under-constrained structure?)",
    -8: "32-bit integer overflow: the problem is too large",
}
_CBWR_AUTO = 2  # MKL_CBWR_AUTO: conditional numerical reproducibility on the code branch MKL picks for this CPU
_P = ctypes.POINTER
_I32 = ctypes.c_int32


@cache
def _library() -> ctypes.CDLL:
    """libmkl_rt: next to this interpreter (pip's `mkl` wheel), else on the loader path."""
    names = ["mkl_rt.*.dll", "libmkl_rt.so*", "libmkl_rt*.dylib"]
    roots = [os.path.join(sys.prefix, "lib"), os.path.join(sys.prefix, "Library", "bin")]
    found = sorted(p for r in roots for n in names for p in glob.glob(os.path.join(r, n)))
    for path in found + ["libmkl_rt.so.3", "libmkl_rt.so.2", "libmkl_rt.so"]:
        try:
            lib = ctypes.CDLL(path)
        except OSError:
            continue
        lib.pardiso.restype = None
        lib.pardiso.argtypes = [_P(ctypes.c_int64)] + [_P(_I32)] * 5 + [ctypes.c_void_p, _P(_I32), _P(_I32),
                                _P(_I32), _P(_I32), _P(_I32), _P(_I32), ctypes.c_void_p, ctypes.c_void_p, _P(_I32)]
        lib.pardisoinit.restype = None
        lib.pardisoinit.argtypes = [_P(ctypes.c_int64), _P(_I32), _P(_I32)]
        lib.MKL_CBWR_Set.restype, lib.MKL_CBWR_Set.argtypes = ctypes.c_int, [ctypes.c_int]
        if "MKL_CBWR" not in os.environ and lib.MKL_CBWR_Set(_CBWR_AUTO) != 0:
            raise SolverError(f"{path}: MKL refused conditional numerical reproducibility (MKL_CBWR_Set)")
        if "MKL_DYNAMIC" not in os.environ:
            lib.MKL_Set_Dynamic.restype, lib.MKL_Set_Dynamic.argtypes = None, [ctypes.c_int]
            lib.MKL_Set_Dynamic(0)
        return lib
    raise SolverError("MKL PARDISO not found: `pip install mkl`, or choose linear_solver='scipy'")


class Pardiso:
    """Cholesky factorization of an SPD matrix given as its upper triangle: scalar CSR, or BSR
    whose block entries hold col >= row with full diagonal blocks."""

    def __init__(self, upper: sp.csr_matrix | sp.bsr_matrix, indefinite: bool = False, single: bool = False) -> None:
        """indefinite=True: an LDL^T factorization of any symmetric matrix, for its `inertia`. single=True: the
        factors in single precision (half the memory; solutions to about 1e-7 relative, a preconditioner for an
        iterative solve in double precision, `linsolve.SPDFactorization(precision="mixed")`)."""
        self._lib = _library()
        self._mtype = _SYMMETRIC if indefinite else _SPD
        self._dtype = np.float32 if single else np.float64  # PARDISO reads the values and vectors in this precision
        self.n = upper.shape[0]
        block = upper.blocksize[0] if sp.issparse(upper) and upper.format == "bsr" else 1
        upper.sort_indices()
        self._data = np.ascontiguousarray(upper.data, dtype=self._dtype)
        self._ia = np.ascontiguousarray(upper.indptr, dtype=np.int32)
        self._ja = np.ascontiguousarray(upper.indices, dtype=np.int32)
        self._rows = self.n // block
        self._pt = np.zeros(64, dtype=np.int64)
        self._iparm = np.zeros(64, dtype=np.int32)
        self._lib.pardisoinit(self._pt.ctypes.data_as(_P(ctypes.c_int64)), ctypes.byref(_I32(self._mtype)),
                              self._iparm.ctypes.data_as(_P(_I32)))
        self._iparm[7] = 0  # no iterative refinement (PARDISO still refines where it perturbed a pivot): the
        # direct solution's residual is 1e-13 relative here, and each refinement step costs a solve
        if indefinite:
            self._iparm[20] = 0  # 1x1 diagonal pivots, not Bunch-Kaufman's 2x2: the path's tangents are positive
            # definite or lose it by a few eigenvalues, and the factorization is faster (docs/validation/timing.md)
        self._iparm[27] = int(single)
        self._iparm[34] = 1  # zero-based indices
        self._iparm[36] = block if block > 1 else 0
        self._alive = True
        self._call(12, np.zeros(self.n))

    def _call(self, phase: int, b: np.ndarray) -> np.ndarray:
        b = np.asfortranarray(b, dtype=self._dtype)  # PARDISO reads columns
        x = np.zeros_like(b)
        err = _I32(0)
        nrhs = 1 if b.ndim == 1 else b.shape[1]
        self._lib.pardiso(
            self._pt.ctypes.data_as(_P(ctypes.c_int64)), ctypes.byref(_I32(1)), ctypes.byref(_I32(1)),
            ctypes.byref(_I32(self._mtype)), ctypes.byref(_I32(phase)), ctypes.byref(_I32(self._rows)),
            self._data.ctypes.data, self._ia.ctypes.data_as(_P(_I32)), self._ja.ctypes.data_as(_P(_I32)),
            None, ctypes.byref(_I32(nrhs)), self._iparm.ctypes.data_as(_P(_I32)), ctypes.byref(_I32(0)),
            b.ctypes.data, x.ctypes.data, ctypes.byref(err),
        )
        if err.value != 0:
            self.close()
            if err.value == -4 or (err.value == -13 and self._mtype == _SPD and phase in (12, 22) and self._indefinite()):
                # -13 is what the parallel Cholesky sometimes returns for a negative pivot: confirmed by the inertia
                raise NotPositiveDefinite(f"PARDISO failed in phase {phase}: {_ERRORS[-4]}")
            raise SolverError(f"PARDISO failed in phase {phase}: {_ERRORS.get(err.value, f'error {err.value}')}")
        return x

    @property
    def alive(self) -> bool:
        """Whether the factorization is held (not yet closed, or closed by an error)."""
        return self._alive

    def _indefinite(self) -> bool:
        """Whether the matrix has a negative eigenvalue (an LDL^T factorization of the same values)."""
        indptr, indices = self._ia, self._ja
        block = self.n // self._rows
        shape = (self.n, self.n)
        upper = (sp.bsr_matrix((self._data, indices, indptr), shape=shape) if block > 1
                 else sp.csr_matrix((self._data, indices, indptr), shape=shape))
        ldl = Pardiso(upper, indefinite=True)
        try:
            return ldl.inertia()[1] > 0
        finally:
            ldl.close()

    def inertia(self) -> tuple[int, int, int]:
        """(positive, negative eigenvalues, perturbed pivots) of an indefinite factorization; with no
        perturbed pivots the counts are exact (Sylvester's law of inertia on L D L^T)."""
        if self._mtype != _SYMMETRIC:
            raise SolverError("inertia needs Pardiso(..., indefinite=True)")
        return int(self._iparm[21]), int(self._iparm[22]), int(self._iparm[13])

    def same_pattern(self, upper: sp.csr_matrix | sp.bsr_matrix) -> bool:
        """Whether `upper` has the sparsity pattern of the first factorization (sorts its indices)."""
        upper.sort_indices()
        return np.array_equal(upper.indptr, self._ia) and np.array_equal(upper.indices, self._ja)

    def refactor(self, upper: sp.csr_matrix | sp.bsr_matrix) -> None:
        """Factor new values on the same sparsity pattern, reusing the ordering and symbolic analysis."""
        if not self.same_pattern(upper):
            raise SolverError("refactor needs the sparsity pattern of the first factorization")
        self._data = np.ascontiguousarray(upper.data, dtype=self._dtype)
        self._call(22, np.zeros(self.n))

    def solve(self, b: np.ndarray) -> np.ndarray:
        """Solution for one (n,) or several (n, r) right-hand sides."""
        return np.ascontiguousarray(self._call(33, b), dtype=np.float64)

    def close(self) -> None:
        """Release the factorization (MKL holds it outside Python's heap)."""
        if self._alive:
            self._alive = False
            self._call(-1, np.zeros(self.n))

    def __del__(self) -> None:
        try:
            self.close()
        except ImportError:  # the interpreter is shutting down and ctypes cannot call any more
            pass
