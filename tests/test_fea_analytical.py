"""The solver against closed-form references: the twisted flat annulus and stress invariants."""

from __future__ import annotations

import numpy as np
import pytest
from helpers_annulus import annulus_k_Nm_per_rad, annulus_mesh, annulus_peak_shear_Pa

from seadesign.fea.loadcases import analyse
from seadesign.fea.stress import invariants, project_to_nodes, vertex_stresses
from seadesign.fea.torsion import solve_unit_torsion

A, B, H = 5.0, 20.0, 4.0  # mm
E, NU = 12e6, 0.48


@pytest.fixture(scope="module")
def mesh():
    return annulus_mesh(A, B, H, n_r=8, n_theta=64, n_z=3)


def _k_error(mesh, order: int, nu: float) -> float:
    sol = solve_unit_torsion(mesh, E, nu, order=order)
    return 1.0 / sol.hub_motion[5] / annulus_k_Nm_per_rad(A, B, H, E, nu) - 1.0


def test_quadratic_stiffness_within_1e_4(mesh):
    assert abs(_k_error(mesh, 2, NU)) < 1e-4  # measured 2.1e-5


def test_linear_elements_lock_at_tpu_poisson_ratio(mesh):
    p1_tpu, p1_soft, p2_tpu = _k_error(mesh, 1, NU), _k_error(mesh, 1, 0.3), _k_error(mesh, 2, NU)
    assert p1_tpu > 0.05  # far too stiff
    assert p1_tpu > p1_soft  # and stiffer the closer nu is to 0.5
    assert p1_tpu > 20 * abs(p2_tpu)


def test_peak_shear_and_l2_projection(mesh):
    sol = solve_unit_torsion(mesh, E, NU)
    at_vertices = vertex_stresses(sol.emesh, sol.displacement_m, E, NU)
    projected = invariants(project_to_nodes(sol.emesh, at_vertices))["max_shear"]
    assert projected.max() == pytest.approx(annulus_peak_shear_Pa(A, H, 1.0), rel=0.03)  # measured 1.1 %

    # L2 projection is closer to tau(r) = T / (2 pi r^2 h) than raw element-vertex values
    r = np.hypot(*sol.emesh.nodes_m[:, :2].T) * 1e-3**-1
    exact_nodes = annulus_peak_shear_Pa(r, H, 1.0)
    raw = invariants(at_vertices.reshape(-1, 6))["max_shear"].reshape(-1, 4)
    exact_raw = exact_nodes[sol.emesh.elements[:, :4]]
    rms = lambda x: float(np.sqrt(np.mean(x**2)))  # noqa: E731
    assert rms(projected / exact_nodes - 1) < rms(raw / exact_raw - 1)


def test_load_cases_on_annulus(mesh):
    torque = 2.0
    res = analyse(mesh, E, NU, 4e6, stall_torque_Nm=torque, impact_torque_Nm=3.0, bearing_radius_mm=A).results.columns()
    k = annulus_k_Nm_per_rad(A, B, H, E, NU)  # measured errors: k 2.1e-5, peak shear 1.1 %, equilibrium 2e-12
    assert res["k_Nm_per_rad"] == pytest.approx(k, rel=1e-4)
    assert res["stall_rotation_rad"] == pytest.approx(torque / k, rel=1e-4)
    assert res["stall_bearing_displacement_mm"] == pytest.approx(torque / k * A, rel=1e-4)
    assert res["equilibrium_rel_error"] < 1e-10
    assert res["stall_max_shear_max_MPa"] == pytest.approx(annulus_peak_shear_Pa(A, H, torque) * 1e-6, rel=0.03)
    # pure shear: von Mises = sqrt(3) tau (measured 2.7e-5), principal stresses +-tau
    assert res["impact_von_mises_max_MPa"] == pytest.approx(np.sqrt(3) * res["impact_max_shear_max_MPa"], rel=2e-4)
    # principal peaks are +-tau plus the discrete pressure error at the bore's rigid edges, which
    # nu = 0.48 amplifies (lambda = 24 mu times a small divergence error): measured +18 % / -35 % here
    tau_impact = annulus_peak_shear_Pa(A, H, 3.0) * 1e-6
    assert res["impact_principal_1_max_MPa"] == pytest.approx(tau_impact, rel=0.4)
    assert res["impact_principal_3_min_MPa"] == pytest.approx(-tau_impact, rel=0.4)
    # the bore is one coupled surface: its resultant force vanishes, the torque goes through it
    assert res["impact_reaction_per_bolt_N"] < 1e-8  # N; measured 4e-10 against the 600 N on the bore
    assert res["safety_factor"] == pytest.approx(4.0 / res["impact_von_mises_max_MPa"], rel=1e-9)


def test_invariants_of_known_tensors():
    tau, p = 3.0, 2.0
    s = np.array([[0, 0, 0, tau, 0, 0], [p, p, p, 0, 0, 0], [5.0, 1.0, -2.0, 0, 0, 0]])
    inv = invariants(s)
    np.testing.assert_allclose(inv["von_mises"], [np.sqrt(3) * tau, 0.0, np.sqrt(0.5 * (16 + 9 + 49))], atol=1e-12)
    np.testing.assert_allclose(inv["principal_1"], [tau, p, 5.0])
    np.testing.assert_allclose(inv["principal_3"], [-tau, p, -2.0])
    np.testing.assert_allclose(inv["max_shear"], [tau, 0.0, 3.5], atol=1e-12)
