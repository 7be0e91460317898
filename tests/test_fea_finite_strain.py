"""Finite-strain elasticity against independent references: finite differences of the energy,
scikit-fem's assembly of the same law written on its own in helpers_skfem (directional derivative
in closed form), the linear model at zero strain, and the linear solver's torsional stiffness."""

from __future__ import annotations

import numpy as np
import pytest
from helpers_annulus import annulus_mesh
from helpers_neo_hooke import neo_hooke_cauchy, uniaxial
from helpers_skfem import neo_hooke_forms, skfem_permutation
from skfem import asm

from seadesign.design.materials import Hyperelastic
from seadesign.fea.assembly import stiffness_upper
from seadesign.fea.elements import element_mesh
from seadesign.fea.finite_strain import Solid
from seadesign.fea.hyperelastic import energy_density, stress, tangent
from seadesign.fea.linsolve import full_from_upper

E, NU = 12e6, 0.48
NEO = Hyperelastic.from_linear(E, NU)
LAWS = {
    "neo_hooke": NEO,
    "mooney_rivlin": Hyperelastic("mooney_rivlin", 1.2e6, 2e-8, "test", c01_Pa=0.6e6),
    "yeoh": Hyperelastic("yeoh", 1.5e6, 2e-8, "test", c20_Pa=-0.1e6, c30_Pa=0.02e6, d2_per_Pa=1e-7, d3_per_Pa=3e-7),
}


def _random_F(n: int, size: float, seed: int = 0) -> np.ndarray:
    return np.eye(3) + size * np.random.default_rng(seed).standard_normal((n, 3, 3))


@pytest.mark.parametrize("name", LAWS)
def test_stress_and_tangent_are_the_derivatives_of_the_energy(name):
    law, F, h = LAWS[name], _random_F(6, 0.3), 1e-6
    P, A = tangent(law, F)
    assert np.array_equal(P, stress(law, F))
    p_fd, a_fd = np.zeros_like(P), np.zeros_like(A)
    for k in range(3):
        for l in range(3):
            d = np.zeros((3, 3))
            d[k, l] = h
            p_fd[..., k, l] = (energy_density(law, F + d) - energy_density(law, F - d)) / (2 * h)
            a_fd[..., k, l] = (stress(law, F + d) - stress(law, F - d)) / (2 * h)
    # central differences: measured 6e-11 to 1.6e-10 of the largest entry
    assert np.abs(P - p_fd).max() < 5e-10 * np.abs(P).max()
    assert np.abs(A - a_fd).max() < 5e-10 * np.abs(A).max()


def test_neo_hooke_from_E_and_nu_is_the_linear_model_at_zero_strain():
    lam, mu = E * NU / ((1 + NU) * (1 - 2 * NU)), E / (2 * (1 + NU))
    _, A = tangent(NEO, np.eye(3)[None])
    i = np.eye(3)
    c = lam * np.einsum("ij,kl->ijkl", i, i) + mu * (np.einsum("ik,jl->ijkl", i, i) + np.einsum("il,jk->ijkl", i, i))
    assert np.abs(A[0] - c).max() < 1e-12 * np.abs(c).max()


# --- scikit-fem: the same compressible neo-Hookean law (CalculiX's NEO HOOKE), written independently ----


@pytest.fixture(scope="module")
def small():
    m = annulus_mesh(5.0, 12.0, 3.0, n_r=2, n_theta=12, n_z=1)
    return m.points_mm * 1e-3, m.tets


def test_residual_and_tangent_equal_scikit_fem(small):
    points, tets = small
    emesh = element_mesh(points, tets, 2)
    x = emesh.nodes_m / 0.012
    u = 0.6e-3 * np.column_stack([np.sin(2 * x[:, 1]) * x[:, 2], x[:, 0] ** 2 - x[:, 2], np.cos(x[:, 0]) * x[:, 1]])
    solid = Solid.of(emesh, NEO)
    forces = solid.forces(u).ravel()
    k = full_from_upper(solid.tangent(u).matrix()).toarray()

    basis, perm = skfem_permutation(points, tets, emesh, intorder=2)  # the 4-point rule, as ours
    residual, stiffness = neo_hooke_forms(NEO.c10_Pa, NEO.d1_per_Pa)
    prev = basis.interpolate(u.ravel()[perm])
    f_ref = asm(residual, basis, prev=prev)
    k_ref = asm(stiffness, basis, prev=prev).toarray()
    assert np.abs(solid.deformation_gradient(u) - np.eye(3)).max() > 0.05  # finite strain (0.09), not the linear limit
    # measured: 2.5e-14 (forces) and 1.3e-15 (tangent) of the largest entry
    assert np.abs(forces[perm] - f_ref).max() < 1e-13 * np.abs(f_ref).max()
    assert np.abs(k[np.ix_(perm, perm)] - k_ref).max() < 1e-14 * np.abs(k_ref).max()


@pytest.mark.parametrize("law, formulation", [("nearly_incompressible", "full"), ("nearly_incompressible", "mean_dilatation"),
                                           ("yeoh", "full"), ("mooney_rivlin", "full"),
                                           ("mooney_rivlin", "mean_dilatation")])
def test_forces_and_tangent_are_derivatives_of_the_energy(small, law, formulation):
    points, tets = small
    emesh = element_mesh(points, tets, 2)
    rng = np.random.default_rng(1)
    u = 5e-5 * rng.standard_normal(emesh.nodes_m.shape)  # |F - I| up to 0.25
    laws = {**LAWS, "nearly_incompressible": Hyperelastic.from_linear(E, 0.499)}
    solid = Solid.of(emesh, laws[law], formulation)
    v = rng.standard_normal(u.shape)
    h = 1e-9
    e_fd = (solid.energy(u + h * v) - solid.energy(u - h * v)) / (2 * h)
    f_fd = (solid.forces(u + h * v) - solid.forces(u - h * v)) / (2 * h)
    assert solid.forces(u).ravel() @ v.ravel() == pytest.approx(e_fd, rel=1e-9)  # measured 1.4e-10, 2.1e-10
    kv = solid.tangent_product(u, v)
    k = full_from_upper(solid.tangent(u).matrix())
    assert np.abs(kv - f_fd).max() < 5e-10 * np.abs(f_fd).max()  # measured 3.9e-11, 1.1e-10
    assert np.abs((k @ v.ravel()).reshape(-1, 3) - kv).max() < 1e-12 * np.abs(kv).max()


def test_tangent_at_rest_is_the_linear_stiffness(small):
    points, tets = small
    emesh = element_mesh(points, tets, 2)
    n = len(emesh.nodes_m)
    for formulation in ("full", "mean_dilatation"):
        k = full_from_upper(Solid.of(emesh, NEO, formulation).tangent(np.zeros((n, 3))).matrix())
        lin = full_from_upper(stiffness_upper(emesh, E, NU).matrix())
        err = abs(k - lin).max() / abs(lin).max()
        if formulation == "full":
            assert err < 1e-12
        else:  # a constant pressure per element: softer, as the mixed P2/P0 element is
            assert 1e-3 < err


GENERAL_F = np.array([[1.3, 0.4, 0.0], [0.1, 0.9, 0.05], [0.0, -0.2, 1.1]])  # J = 1.25: every principal stress tensile


@pytest.mark.parametrize("formulation", ["full", "mean_dilatation"])
@pytest.mark.parametrize("F", [GENERAL_F, GENERAL_F / np.linalg.det(GENERAL_F) ** (1 / 3)], ids=["dilated", "isochoric"])
def test_element_strain_and_cauchy_von_mises_of_a_homogeneous_deformation(small, formulation, F):
    """u = (F - I) X: every quadrature point has this F. The principal stretches are F's singular values along
    b = F F^T's eigenvectors n; the Cauchy stress is the closed-form neo-Hookean one, whose n sigma n signs tell
    tension from compression (von Mises: that of its deviatoric part)."""
    points, tets = small
    emesh = element_mesh(points, tets, 2)
    u = emesh.nodes_m @ (F - np.eye(3)).T
    result = Solid.of(emesh, NEO, formulation).element_strain_stress(u)
    sigma = neo_hooke_cauchy(NEO, F)
    lam2, n = np.linalg.eigh(F @ F.T)
    principal = np.array([n[:, i] @ sigma @ n[:, i] for i in range(3)])
    stretch = np.sqrt(lam2)
    tensile = max((stretch[i] - 1 for i in range(3) if principal[i] > 0), default=0.0)
    compressive = max((1 - stretch[i] for i in range(3) if principal[i] < 0), default=0.0)
    dev = sigma - np.trace(sigma) / 3 * np.eye(3)
    # measured: 4e-16 and 2e-15 relative (round-off)
    assert np.allclose(result.tensile_strain, tensile, rtol=1e-12, atol=0)
    assert np.allclose(result.compressive_strain, compressive, rtol=1e-12, atol=0)
    assert np.allclose(result.von_mises_Pa, np.sqrt(1.5 * np.sum(dev * dev)), rtol=1e-12, atol=0)


@pytest.mark.parametrize("axial", [0.6, 0.85, 1.2, 1.6])
def test_a_block_in_uniaxial_compression_has_no_tensile_strain_and_in_tension_its_stretch(small, axial):
    """A block squeezed to `axial` with free lateral faces bulges sideways (lateral stretch > 1, zero lateral
    stress): the tensile criterion is 0, not the bulge, and the compression is 1 - axial. Pulled, the tensile
    criterion is axial - 1 and the lateral contraction carries no stress, so no compression counts."""
    points, tets = small
    emesh = element_mesh(points, tets, 2)
    F = uniaxial(NEO, axial)
    assert F[1, 1] > 1.0 if axial < 1 else F[1, 1] < 1.0  # the bulge (or the contraction) is there
    result = Solid.of(emesh, NEO, "full").element_strain_stress(emesh.nodes_m @ (F - np.eye(3)).T)
    tensile, compressive = (0.0, 1 - axial) if axial < 1 else (axial - 1, 0.0)
    assert np.allclose(result.tensile_strain, tensile, rtol=1e-12, atol=1e-12)
    assert np.allclose(result.compressive_strain, compressive, rtol=1e-12, atol=1e-12)
