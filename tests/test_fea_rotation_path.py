"""The rotation-driven large-deflection path against independent references: Rivlin's circular shear
of an incompressible neo-Hookean annulus, the linear solver's stiffness at rest with the same hub
constraints, and the eigenvalues of the tangent where the path says a buckling mode appears."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse.linalg as sla
from helpers_annulus import E, H_MM, annulus_mesh, circular_shear, radial_drift

from seadesign.design.materials import Hyperelastic
from seadesign.fea.assembly import stiffness_upper
from seadesign.fea.couplings import couple
from seadesign.fea.linsolve import full_from_upper
from seadesign.fea.rotation_path import PathSettings, path_problem, rotation_path
from seadesign.fea.torsion import MM

def test_circular_shear_torque_stays_linear_to_one_radian():
    # Rivlin: phi(a) = T / (4 pi mu h) (1/a^2 - 1/b^2) at any rotation (the shear response of neo-Hooke is linear)
    path, t1, _ = circular_shear(4, 48, 0.4999, "mean_dilatation")
    assert path.stop_reason == "target_reached"
    assert path.rotation_at(t1) == pytest.approx(1.0, abs=0.01)  # measured 0.9964 on this coarse mesh
    for p in path.points[1:]:
        assert p.torque_Nm == pytest.approx(t1 * p.rotation_rad, rel=0.01)
    assert radial_drift(path).max() < 0.01  # measured 0.0044 (0.0011 on 10 x 120, second order)


def test_full_integration_locks_near_incompressibility():
    # the displacement-only P2 element with U(J) at every point is 7 % too stiff at 1 rad for nu = 0.4999;
    # the mean dilatation (one pressure per element) is not: the formulation that keeps P2 free of locking
    path, t1, _ = circular_shear(4, 48, 0.4999, "full")
    assert path.rotation_at(t1) < 0.97  # measured 0.942


@pytest.mark.slow
def test_circular_shear_keeps_points_on_circles_and_the_normal_stress_difference():
    from seadesign.fea.finite_strain import Solid
    from seadesign.fea.hyperelastic import stress

    path, t1, mu = circular_shear(12, 144, 0.4999, "mean_dilatation")
    assert path.rotation_at(t1) == pytest.approx(1.0, abs=1e-3)
    assert radial_drift(path).max() < 1e-3  # points stay on their circles: < 0.1 % of the arc at 1 rad
    # sigma_tt - sigma_rr = mu gamma^2, gamma = T / (2 pi mu h r^2), averaged over rings of the deformed annulus
    solid = Solid.of(path.emesh, Hyperelastic.from_linear(E, 0.4999), "mean_dilatation")
    u = path.displacement_m
    F = solid.deformation_gradient(u)
    sig = stress(solid.law, F) @ np.swapaxes(F, -1, -2) / np.linalg.det(F)[..., None, None]
    from seadesign.fea.elements import quadrature, shape_values

    n = shape_values(2, quadrature(2)[0])
    x = np.einsum("qa,mai->mqi", n, (path.emesh.nodes_m + u)[path.emesh.elements])
    ang = np.arctan2(x[..., 1], x[..., 0])
    er = np.stack([np.cos(ang), np.sin(ang), 0 * ang], -1)
    et = np.stack([-np.sin(ang), np.cos(ang), 0 * ang], -1)
    diff = np.einsum("mqi,mqij,mqj->mq", et, sig, et) - np.einsum("mqi,mqij,mqj->mq", er, sig, er)
    r = np.hypot(x[..., 0], x[..., 1])
    gamma = path.points[-1].torque_Nm / (2 * np.pi * mu * H_MM * MM * r**2)
    bins = np.digitize(r, np.linspace(11e-3, 19e-3, 9))
    for k in range(1, 9):
        ring = bins == k
        assert diff[ring].mean() == pytest.approx((mu * gamma[ring] ** 2).mean(), rel=0.02)


def test_tangent_at_rest_equals_the_linear_k_with_the_same_hub_constraints():
    # the linear solver's rigid coupling with the hub's translation and tilt held: k = 1 / (K^-1)_zz
    mesh = annulus_mesh(5.0, 12.0, 3.0, n_r=3, n_theta=16, n_z=2)
    path = rotation_path(mesh, Hyperelastic.from_linear(E, 0.48), 1e-3)
    p = path_problem(mesh, Hyperelastic.from_linear(E, 0.48), PathSettings())
    em = p.solid.mesh
    cpl = couple(em.nodes_m, p.drive.hub, p.drive.ring, np.array([0.0, 0.0, 1.5e-3]))
    k = full_from_upper(cpl.condense(stiffness_upper(em, E, 0.48, cpl.node_index, cpl.n_rows)).matrix()).tocsc()
    keep = np.setdiff1d(np.arange(k.shape[0]), cpl.ref_dofs[:5])  # hold t and the tilts
    rhs = np.zeros(len(keep))
    rhs[-1] = 1.0
    theta = sla.spsolve(k[keep][:, keep], rhs)[-1]
    assert path.points[0].tangent_Nm_per_rad == pytest.approx(1.0 / theta, rel=1e-9)  # measured 2e-12


def test_a_thin_plate_in_torsion_stops_where_the_tangent_loses_stability():
    # a 0.3 mm annular plate wrinkles under torsion: the path must stop as a bifurcation, with the
    # smallest eigenvalue of the free nodes' tangent (scipy, shift-invert) near zero there and positive at rest
    mesh = annulus_mesh(10.0, 20.0, 0.3, 4, 48, 1)
    law = Hyperelastic.from_linear(E, 0.45)
    path = rotation_path(mesh, law, 50.0, PathSettings(max_step_rad=0.05))
    assert path.stop_reason == "bifurcation"
    p = path_problem(mesh, law, PathSettings())

    def smallest(u):
        k = full_from_upper(p.solid.tangent(u, p.system.pattern).matrix()).tocsc()
        return sla.eigsh(k, k=1, sigma=0, which="LM", return_eigenvectors=False)[0]

    at_rest, at_stop = smallest(np.zeros_like(path.displacement_m)), smallest(path.displacement_m)
    assert at_rest > 0 and 0 < at_stop < 0.05 * at_rest
    assert path.points[-1].tangent_Nm_per_rad > 0.9 * path.points[0].tangent_Nm_per_rad  # no torque maximum


def test_a_path_has_the_same_digits_on_one_or_two_blas_threads():
    # OpenBLAS sums a long dot product in an order set by its thread count; the path runs on one BLAS thread so that
    # the machine's cores do not move its last digits (without it, 1 and 2 threads differ here by up to 1.8e-15 Nm)
    from threadpoolctl import ThreadpoolController

    openblas = ThreadpoolController().select(internal_api="openblas")
    mesh = annulus_mesh(10.0, 20.0, H_MM, 6, 96, 2)  # 37,440 unknowns: long enough for OpenBLAS to split its sums
    paths = []
    for threads in (1, 2):
        with openblas.limit(limits=threads):
            if threads > 1 and max(i["num_threads"] for i in openblas.info()) < 2:
                pytest.skip("OpenBLAS runs on one thread on this machine: nothing to compare")
            paths.append(rotation_path(mesh, Hyperelastic.from_linear(E, 0.45), 1e9,
                                       PathSettings(max_rotation_rad=0.3, max_step_rad=0.1)))
    one, two = paths
    assert [p.torque_Nm for p in one.points] == [p.torque_Nm for p in two.points]
    assert np.array_equal(one.displacement_m, two.displacement_m)
