"""Block-upper assembly, rigid condensation and the PARDISO binding against independent
references: scikit-fem's assembler, an explicit T^T K T, the patch test and SciPy's solver."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
from helpers_annulus import annulus_mesh
from helpers_skfem import skfem_permutation
from skfem import asm
from skfem.models.elasticity import lame_parameters, linear_elasticity

from seadesign.errors import SolverError
from seadesign.fea.assembly import add_pair_blocks, mass_upper, nodal_forces, stiffness_upper
from seadesign.fea.couplings import couple
from seadesign.fea.elements import element_mesh
from seadesign.fea.linsolve import SPDFactorization, full_from_upper

E, NU = 12e6, 0.48


@pytest.fixture(scope="module")
def small():
    m = annulus_mesh(5.0, 12.0, 3.0, n_r=2, n_theta=12, n_z=1)
    return m.points_mm * 1e-3, m.tets


@pytest.mark.parametrize("order", [1, 2])
def test_stiffness_equals_scikit_fem(small, order):
    points, tets = small
    emesh = element_mesh(points, tets, order)
    ours = full_from_upper(stiffness_upper(emesh, E, NU).matrix()).toarray()
    basis, perm = skfem_permutation(points, tets, emesh)
    ref = asm(linear_elasticity(*lame_parameters(E, NU)), basis).toarray()
    mine = ours[np.ix_(perm, perm)]
    assert np.abs(mine - ref).max() < 1e-9 * np.abs(ref).max()


def test_pair_blocks_add_to_the_dense_matrix_and_join_the_pattern(small):
    # symmetric 9 x 9 node groups (nodes repeated within a group, groups repeated, some nodes held, most pairs of
    # nodes far apart and outside the stiffness's pattern) added to the stiffness, against dense addition
    points, tets = small
    emesh = element_mesh(points, tets, 2)
    n = len(emesh.nodes_m)
    rng = np.random.default_rng(3)
    held = rng.choice(n, n // 10, replace=False)
    index = np.full(n, -1)
    free = np.setdiff1d(np.arange(n), held)
    index[free] = np.arange(len(free))
    upper = stiffness_upper(emesh, E, NU, index, len(free))
    nodes = rng.integers(0, n, size=(40, 9))
    nodes[5, 3] = nodes[5, 7]
    nodes[6] = nodes[7]
    half = rng.normal(size=(40, 27, 27))
    blocks = (half + half.transpose(0, 2, 1)).reshape(40, 9, 3, 9, 3).transpose(0, 1, 3, 2, 4)
    dense = full_from_upper(upper.matrix()).toarray()
    for p in range(40):
        for a in range(9):
            for b in range(9):
                i, j = index[nodes[p, a]], index[nodes[p, b]]
                if i >= 0 and j >= 0:
                    dense[3 * i:3 * i + 3, 3 * j:3 * j + 3] += blocks[p, a, b]
    summed = add_pair_blocks(upper, index, nodes, blocks)
    assert len(summed.rows) > len(upper.rows)
    assert np.all(np.diff(summed.rows.astype(np.int64) * summed.n + summed.cols) > 0)  # sorted, each entry once
    assert np.abs(full_from_upper(summed.matrix()).toarray() - dense).max() < 1e-12 * np.abs(dense).max()


def test_patch_test_energy_and_interior_forces(small):
    points, tets = small
    emesh = element_mesh(points, tets, 2)
    k = full_from_upper(stiffness_upper(emesh, E, NU).matrix())
    grad = np.array([[1.0, 0.3, -0.2], [0.1, -0.5, 0.4], [0.2, 0.0, 0.7]]) * 1e-3
    u = emesh.nodes_m @ grad.T
    eps = 0.5 * (grad + grad.T)
    lam, mu = E * NU / ((1 + NU) * (1 - 2 * NU)), E / (2 * (1 + NU))
    volume = np.pi * (0.012**2 - 0.005**2) * 0.003 * (np.sin(2 * np.pi / 12) * 12 / (2 * np.pi))  # 12-gon annulus
    energy = volume * (lam * np.trace(eps) ** 2 + 2 * mu * np.sum(eps * eps))
    assert u.ravel() @ (k @ u.ravel()) == pytest.approx(energy, rel=1e-9)
    r = np.hypot(*emesh.nodes_m[:, :2].T)
    z = emesh.nodes_m[:, 2]  # chord midpoints of the outer 12-gon lie at r = 11.6 mm
    interior = (r > 0.0051) & (r < 0.011) & (z > 1e-6) & (z < 0.003 - 1e-6)
    f = (k @ u.ravel()).reshape(-1, 3)
    assert interior.any() and np.abs(f[interior]).max() < 1e-9 * np.abs(f).max()


def test_condensation_and_solve_match_explicit_transform(small):
    points, tets = small
    emesh = element_mesh(points, tets, 2)
    r = np.hypot(*emesh.nodes_m[:, :2].T)
    hub, ring = np.flatnonzero(r < 0.0051), np.flatnonzero(r > 0.0119)
    ref = np.array([0.0, 0.0, 0.0015])
    cpl = couple(emesh.nodes_m, hub, ring, ref)
    reduced = full_from_upper(cpl.condense(stiffness_upper(emesh, E, NU, cpl.node_index, cpl.n_rows)).matrix())

    # explicit u = T q over all nodes: free dofs identity, hub nodes t + w x (x - ref), ring held
    n = len(emesh.nodes_m)
    free = np.setdiff1d(np.arange(n), np.union1d(hub, ring))
    t = np.zeros((3 * n, 3 * len(free) + 6))
    for i, node in enumerate(free):
        t[3 * node : 3 * node + 3, 3 * i : 3 * i + 3] = np.eye(3)
    for node in hub:
        d = emesh.nodes_m[node] - ref
        t[3 * node : 3 * node + 3, -6:-3] = np.eye(3)
        t[3 * node : 3 * node + 3, -3:] = -np.array([[0, -d[2], d[1]], [d[2], 0, -d[0]], [-d[1], d[0], 0]])
    k_full = full_from_upper(stiffness_upper(emesh, E, NU).matrix()).toarray()
    explicit = t.T @ k_full @ t
    assert np.abs(reduced.toarray() - explicit).max() < 1e-9 * np.abs(explicit).max()

    rhs = np.zeros(reduced.shape[0])
    rhs[cpl.ref_dofs[5]] = 1.0
    expected = np.linalg.solve(explicit, rhs)
    upper = cpl.condense(stiffness_upper(emesh, E, NU, cpl.node_index, cpl.n_rows)).matrix()
    for backend, precision in (("pardiso", "double"), ("pardiso", "mixed"), ("scipy", "double")):
        fact = SPDFactorization(upper, backend=backend, precision=precision)
        q = fact.solve(rhs)
        fact.close()
        assert np.abs(q - expected).max() < 1e-8 * np.abs(expected).max()  # single-precision factors alone: 1e-6

    u = cpl.displacements(expected)
    assert np.allclose(u.ravel(), t @ expected)
    f = nodal_forces(emesh, u, E, NU, np.union1d(hub, ring))
    full = (k_full @ u.ravel()).reshape(-1, 3)
    assert np.allclose(f[hub], full[hub], atol=1e-9) and np.allclose(f[ring], full[ring], atol=1e-9)
    torque = lambda nodes: np.sum(emesh.nodes_m[nodes, 0] * f[nodes, 1] - emesh.nodes_m[nodes, 1] * f[nodes, 0])  # noqa: E731
    assert torque(hub) == pytest.approx(1.0, rel=1e-9) and torque(ring) == pytest.approx(-1.0, rel=1e-9)


def _conditioned(condition: float, n: int = 60) -> tuple[sp.csr_matrix, np.ndarray, np.ndarray]:
    """An SPD matrix (upper CSR) with eigenvalues from 1 to `condition`, a load and LAPACK's solution."""
    rng = np.random.default_rng(0)
    q, _ = np.linalg.qr(rng.standard_normal((n, n)))
    a = q @ np.diag(np.logspace(0, np.log10(condition), n)) @ q.T
    b = rng.standard_normal(n)
    return sp.csr_matrix(np.triu(a)), b, np.linalg.solve(a, b)


@pytest.mark.parametrize("condition, maxiter", [(1e9, None), (1e7, 1)])
def test_mixed_precision_falls_back_to_double_where_single_precision_fails(monkeypatch, condition, maxiter):
    """Cond 1e9: the single-precision Cholesky meets a negative pivot; cond 1e7 with one iteration allowed: the
    refinement does not converge. Either way the answer is the double-precision one, never an error or a guess."""
    import seadesign.fea.linsolve as linsolve

    if maxiter is not None:
        monkeypatch.setattr(linsolve, "MIXED_MAXITER", maxiter)
    upper, b, x = _conditioned(condition)
    y = SPDFactorization(upper, precision="mixed").solve(b)
    assert np.abs(y - x).max() < 1e-7 * np.abs(x).max()  # LAPACK's own error here: 3e-9 (cond 1e9)


def test_mixed_precision_needs_pardiso():
    upper, _, _ = _conditioned(10.0)
    with pytest.raises(SolverError, match="'mixed' with 'pardiso'"):
        SPDFactorization(upper, backend="scipy", precision="mixed")


def test_mass_matrix_integrates_volume(small):
    points, tets = small
    emesh = element_mesh(points, tets, 2)
    m = full_from_upper(mass_upper(emesh).matrix())
    one = np.ones(m.shape[0])
    volume = np.sum(np.abs(np.linalg.det(points[tets[:, 1:]] - points[tets[:, :1]]))) / 6
    assert one @ (m @ one) == pytest.approx(volume, rel=1e-12)


def test_pardiso_refuses_a_matrix_that_is_not_positive_definite(small):
    points, tets = small
    emesh = element_mesh(points, tets, 2)
    r = np.hypot(*emesh.nodes_m[:, :2].T)
    cpl = couple(emesh.nodes_m, np.flatnonzero(r < 0.0051), np.flatnonzero(r > 0.0119), np.zeros(3))
    k = cpl.condense(stiffness_upper(emesh, E, NU, cpl.node_index, cpl.n_rows)).matrix()
    with pytest.raises(SolverError, match="not positive definite"):
        SPDFactorization(-k)


@pytest.mark.parametrize("negatives", [0, 1, 7])
def test_pardiso_inertia_counts_the_negative_eigenvalues(small, negatives):
    """The LDL^T inertia (which decides a path's stability) against LAPACK's eigenvalues: the coupled
    stiffness shifted so that `negatives` (or the next count between distinct eigenvalues) fall below zero."""
    from seadesign.fea.pardiso import Pardiso

    points, tets = small
    emesh = element_mesh(points, tets, 2)
    r = np.hypot(*emesh.nodes_m[:, :2].T)
    cpl = couple(emesh.nodes_m, np.flatnonzero(r < 0.0051), np.flatnonzero(r > 0.0119), np.zeros(3))
    k = cpl.condense(stiffness_upper(emesh, E, NU, cpl.node_index, cpl.n_rows)).matrix()
    ev = np.linalg.eigvalsh(full_from_upper(k).toarray())  # the annulus's symmetry pairs some of them
    while negatives and ev[negatives] - ev[negatives - 1] < 1e-3 * ev[negatives]:
        negatives += 1  # a shift inside a double eigenvalue would not say how many fall below it
    shift = 0.5 * (ev[negatives - 1] + ev[negatives]) if negatives else 0.5 * ev[0]
    shifted = (k.tocsr() - shift * sp.eye(k.shape[0], format="csr")).tobsr(blocksize=(3, 3))
    ldl = Pardiso(shifted, indefinite=True)
    try:
        positive, negative, perturbed = ldl.inertia()
    finally:
        ldl.close()
    assert (positive, negative, perturbed) == (k.shape[0] - negatives, negatives, 0)


def test_pardiso_gives_the_same_digits_every_time_on_several_threads():
    """MKL's reproducibility mode is on, with a fixed number of threads; without it, PARDISO's four-thread factorization of this matrix (a shifted
    3D Laplacian, 47k unknowns) gave solutions that differ in the last digit within 10 repeats in 4 of 6 runs."""
    import ctypes

    from threadpoolctl import threadpool_limits

    from seadesign.fea.pardiso import _CBWR_AUTO, Pardiso, _library

    lib = _library()
    lib.MKL_CBWR_Get.restype, lib.MKL_CBWR_Get.argtypes = ctypes.c_int, [ctypes.c_int]
    assert lib.MKL_CBWR_Get(1) == _CBWR_AUTO  # MKL_CBWR_BRANCH: the code branch in use
    lib.MKL_Get_Dynamic.restype, lib.MKL_Get_Dynamic.argtypes = ctypes.c_int, []
    assert lib.MKL_Get_Dynamic() == 0  # a fixed number of threads, as reproducibility needs

    n = 36
    line, one = sp.diags([-1.0, 2.2, -1.0], [-1, 0, 1], shape=(n, n)), sp.identity(n)
    rng = np.random.default_rng(0)
    a = (sp.kron(sp.kron(line, one), one) + sp.kron(sp.kron(one, line), one) + sp.kron(sp.kron(one, one), line)
         + sp.diags(rng.random(n**3)))
    upper, b = sp.triu(a, format="csr"), rng.random(n**3)
    solutions = []
    with threadpool_limits(4):
        for _ in range(10):
            f = Pardiso(upper.copy())
            solutions.append(f.solve(b))
            f.close()
    assert all(np.array_equal(solutions[0], x) for x in solutions[1:])
