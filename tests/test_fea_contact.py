"""Frictionless contact against independent references: PyTorch's automatic derivatives of the gap, finite
differences of the contact energy, the contact patch test (a block pressed onto a flat face takes the closed-form
homogeneous uniaxial state of the neo-Hookean law, helpers_neo_hooke) on conforming and non-conforming meshes, and
Hertz's cylinder on a flat."""

from __future__ import annotations

import numpy as np
import pytest
from helpers_contact import half_cylinder_on_flat, two_blocks
from helpers_neo_hooke import neo_hooke_cauchy, uniaxial

from seadesign.design.materials import Hyperelastic
from seadesign.errors import ConfigError, NotPositiveDefinite
from seadesign.fea.contact import ContactSettings, ContactSurface, FrictionlessContact, Multipliers
from seadesign.fea.contact_geometry import plane_gap
from seadesign.fea.elements import element_mesh, midside_nodes
from seadesign.fea.equilibrium import Equilibrium
from seadesign.fea.finite_strain import Solid
from seadesign.fea.newton import newton_augmented
from seadesign.fea.torsion import MM

LAW = Hyperelastic.from_linear(10e6, 0.45)
GAP_MM, SQUEEZE_MM = 0.01, 0.05  # the top block starts 0.01 mm above the base; its top face is pushed 0.06 mm down


def test_plane_gap_gradient_and_hessian_equal_automatic_differentiation():
    torch = pytest.importorskip("torch")
    rng = np.random.default_rng(0)
    d, e1, e2 = (rng.normal(size=(5, 3)) for _ in range(3))
    g, grad, hess = plane_gap(d, e1, e2)

    def gap(y):
        m = torch.linalg.cross(y[1], y[2])
        return y[0] @ (m / torch.linalg.norm(m))

    for k in range(5):
        y = torch.tensor(np.stack([d[k], e1[k], e2[k]]), dtype=torch.float64)
        assert gap(y).item() == pytest.approx(g[k], abs=1e-14)
        assert np.abs(torch.autograd.functional.jacobian(gap, y).numpy() - grad[k]).max() < 1e-14  # measured 4e-16
        h = torch.autograd.functional.hessian(gap, y).numpy().transpose(0, 2, 1, 3)
        assert np.abs(h - hess[k]).max() < 1e-13  # measured 2e-15


def _blocks(base_cells: int, top_cells: int, rigid_base: bool, settings: ContactSettings = ContactSettings()):
    """The two blocks with the top face pushed down and stretched laterally as the homogeneous uniaxial state asks;
    the base held (all of it, or its bottom face). Returns the system, the exact state and node sets."""
    mesh, _, _ = two_blocks((base_cells, base_cells, 2), (top_cells, top_cells, 2), gap_mm=GAP_MM)
    em = element_mesh(mesh.points_mm * MM, mesh.tets, 2)
    base_tets = 6 * base_cells**2 * 2
    base, top = np.unique(em.elements[:base_tets]), np.unique(em.elements[base_tets:])
    x = em.nodes_m
    top_face = top[np.isclose(x[top, 2], (1 + GAP_MM) * MM, rtol=0, atol=1e-12)]
    F = uniaxial(LAW, 1 - SQUEEZE_MM)[[1, 2, 0]][:, [1, 2, 0]]  # diag(s, s, stretch): the axis is z
    exact = np.column_stack([(F[0, 0] - 1) * x[:, 0], (F[1, 1] - 1) * x[:, 1],
                             (F[2, 2] - 1) * (x[:, 2] - GAP_MM * MM) - GAP_MM * MM])
    held = base if rigid_base else base[np.isclose(x[base, 2], -MM, rtol=0, atol=1e-12)]
    prescribed = np.union1d(top_face, held)
    contact = FrictionlessContact.of(ContactSurface.of(em, mesh.boundary_faces, prescribed), LAW.shear_modulus_Pa,
                                     settings)
    system = Equilibrium.of(Solid.of(em, LAW), prescribed, top_face, 1e-10, contact=contact)
    u0 = np.zeros_like(x)
    u0[top] = exact[top]
    return system, u0, exact, F, em, mesh, top


def _consistent_load(em, mesh, z_mm: float) -> np.ndarray:
    """The nodal loads of a unit pressure on the boundary faces at height z: the quadratic face's are 0 at its
    corners and a third of its area at each midside node."""
    load = np.zeros(len(em.nodes_m))
    x = em.nodes_m
    for face in mesh.boundary_faces[np.all(np.isclose(x[mesh.boundary_faces][:, :, 2], z_mm * MM, atol=1e-12), axis=1)]:
        area = 0.5 * np.linalg.norm(np.cross(x[face[1]] - x[face[0]], x[face[2]] - x[face[0]]))
        for i, j in ((0, 1), (1, 2), (2, 0)):
            load[midside_nodes(em, face[[i]], face[[j]])[0]] += area / 3
    return load


@pytest.mark.parametrize("base_cells, top_cells", [(2, 2), (2, 3), (3, 2)])
def test_patch_a_block_pressed_on_a_rigid_face_takes_the_uniform_pressure(base_cells, top_cells):
    # conforming (2, 2) and non-conforming meshes: the contact forces on the block are the consistent loads of the
    # closed-form pressure and the block's state the homogeneous one, to the augmented Lagrangian's penetration
    system, u0, exact, F, em, mesh, top = _blocks(base_cells, top_cells, True, ContactSettings(penetration_tol_mm=1e-9,
                                                                                            max_augmentations=60))
    result = newton_augmented(system, u0)
    assert result.status == "converged"
    pressure = -neo_hooke_cauchy(LAW, F)[2, 2] * F[0, 0] * F[1, 1]  # per rest area
    load = pressure * _consistent_load(em, mesh, GAP_MM)
    bottom = np.flatnonzero(load > 0)
    force = system.contact.forces(result.u)
    assert np.abs(force[bottom, 2] + load[bottom]).max() < 1e-6 * load.max()  # measured 1.7e-7 to 3.1e-7
    assert np.abs(force[:, :2]).max() < 1e-12 * load.max()  # frictionless: no tangential force at all
    assert np.abs(result.u[top] - exact[top]).max() < 2e-7 * SQUEEZE_MM * MM  # measured 3.7e-8 to 4.8e-8
    assert system.contact.summary(result.u).area_m2 == pytest.approx(MM**2, rel=1e-12)  # the 1 x 1 mm footprint
    # the pairs' normal force: the closed-form pressure on the footprint (measured 7e-11 to 3.0e-10)
    assert system.contact.normal_force_N(result.u) == pytest.approx(pressure * MM**2, rel=1e-9)


def test_a_deformable_base_carries_the_same_total_load():
    # both blocks elastic (the base's bottom held): the load's spread on the base's nodes is the flat facets'
    # (linear), not the quadratic face's, so neither block is homogeneous and the quadratic faces cannot close on
    # the flat facets at every Gauss point: on this conforming mesh the multiplier updates stall near 6 nm of
    # penetration (17 nm at penalty factor 10), a limit of the formulation far below the default tolerance
    system, u0, exact, F, em, mesh, top = _blocks(2, 2, False, ContactSettings(penalty_factor=30.0, penetration_tol_mm=2e-5,
                                                                               max_augmentations=100))
    result = newton_augmented(system, u0)
    assert result.status == "converged"
    reaction = -result.forces[system.reaction, 2].sum()
    base_load = result.forces[np.isclose(em.nodes_m[:, 2], -MM, atol=1e-12), 2].sum()
    assert reaction == pytest.approx(base_load, rel=1e-9)  # action and reaction across the contact: measured 1e-14


def test_forces_and_tangent_are_the_derivatives_of_the_contact_energy():
    system, u0, exact, F, em, mesh, top = _blocks(2, 3, True, ContactSettings())
    contact = system.contact
    rng = np.random.default_rng(1)
    u = u0 + rng.normal(scale=2e-7, size=u0.shape)  # penetrating, by about 10 um
    contact.assignment = contact.search(u)
    q, f = contact.assignment
    contact.multipliers = Multipliers(q * len(contact.surface.facets) + f, rng.uniform(0, 1e5, size=len(q)))
    f = contact.forces(u)
    assert contact.active(u).shape[0] > 20
    nodes, blocks = contact.tangent_blocks(u)
    v = rng.normal(size=u.shape) * 1e-9
    kv = np.zeros_like(u)
    np.add.at(kv, nodes, np.einsum("pabij,pbj->pai", blocks, v[nodes]))
    h = 1e-3
    de = (contact.energy(u + h * v) - contact.energy(u - h * v)) / (2 * h)
    assert de == pytest.approx(np.sum(f * v), rel=1e-7)
    df = (contact.forces(u + h * v) - contact.forces(u - h * v)) / (2 * h)
    assert np.abs(df - kv).max() < 1e-6 * np.abs(kv).max()


def test_the_first_pass_over_the_vertices_loses_no_pair_that_can_press():
    """The search looks only at faces near a facing vertex (`near_mm`); with the blocks pressed and sheared
    sideways by a random field, the pairs within 20 um (pressed or about to be) are those of a search over every
    face (`near_mm` beyond the part)."""
    system, u0, *_ = _blocks(2, 3, False)
    u = u0 + np.random.default_rng(2).normal(scale=2e-6, size=u0.shape)
    everywhere = FrictionlessContact.of(system.contact.surface, LAW.shear_modulus_Pa, ContactSettings(near_mm=100.0))

    def close(contact):
        pairs = contact.pairs(u, contact.search(u))
        return set(zip(pairs.point[pairs.gap_m < 20e-6], pairs.facet[pairs.gap_m < 20e-6]))

    found = close(system.contact)
    assert len(found) > 40 and found == close(everywhere)


@pytest.mark.parametrize("depth_mm, paired", [(0.09, True), (0.11, False)])
def test_a_point_deeper_behind_a_facet_than_the_search_distance_is_not_paired(depth_mm, paired):
    """A point further than `search_mm` (0.1 mm) behind a facet's plane came into the facet's prism from the side
    (at a fold of the surface), it did not cross the facet: the top block moved down into the base by `depth_mm`
    has its bottom paired with the base's top within that depth only."""
    system, u0, *_ = _blocks(2, 2, True)
    top = np.unique(system.solid.mesh.elements[6 * 2**2 * 2:])
    u = np.zeros_like(u0)
    u[top, 2] = -(GAP_MM + depth_mm) * MM
    points, facets = system.contact.search(u)
    assert (len(points) > 0) == paired


def test_multipliers_are_extrapolated_linearly_and_never_below_zero():
    before = Multipliers(np.array([1, 4]), np.array([2.0, 5.0]))
    last = Multipliers(np.array([1, 4, 7]), np.array([3.0, 1.0, 6.0]))  # pair 7 is new: it had 0
    ahead = last.extrapolated(before, 0.5)
    np.testing.assert_array_equal(ahead.keys, last.keys)
    np.testing.assert_allclose(ahead.values_Pa, [3.5, 0.0, 9.0])  # 1 + 0.5 (1 - 5) = -1 is held at 0
    assert last.extrapolated(before, 0.0) is last


def test_the_answer_does_not_depend_on_the_penalty():
    reactions = []
    for factor in (10.0, 30.0):  # measured: reactions 4e-8 apart
        system, u0, *_ = _blocks(2, 3, False, ContactSettings(penalty_factor=factor, penetration_tol_mm=1e-8,
                                                                  max_augmentations=100))
        result = newton_augmented(system, u0)
        assert result.status == "converged"
        reactions.append(result.forces[system.reaction, 2].sum())
    assert reactions[0] == pytest.approx(reactions[1], rel=1e-6)


@pytest.mark.parametrize("key, value", [("penalty_factor", 0.0), ("penetration_tol_mm", -1e-3), ("search_mm", 0.0),
                                        ("max_augmentations", 0)])
def test_a_contact_setting_out_of_range_is_refused_naming_the_key(key, value):
    with pytest.raises(ConfigError, match=key):
        ContactSettings(**{key: value})


def _hertz(h_mm: float) -> tuple[float, float]:
    """A neo-Hookean half cylinder (R = 10 mm, plane strain: u_z = 0) whose top face is pushed 0.05 mm down onto a
    rigid flat: the contact half-width and peak pressure relative to Hertz's for the measured line load,
    a = sqrt(4 P R / (pi E*)) and p0 = 2 P / (pi a) with E* = E / (1 - nu^2), minus 1. The finite-element pair is
    read from the pressures of the pressed Gauss points by the least-squares fit of p^2 = p0^2 (1 - x^2 / a^2) to
    those above a fifth of the largest (a single Gauss point's pressure oscillates, see the test)."""
    radius_mm, thickness_mm, push_mm = 10.0, 0.1, 0.05
    mesh, flat = half_cylinder_on_flat(radius_mm, thickness_mm, h_mm)
    em = element_mesh(mesh.points_mm * MM, mesh.tets, 2)
    x = em.nodes_m
    top = np.flatnonzero(np.isclose(x[:, 1], 0.0, rtol=0, atol=1e-12))
    prescribed = np.union1d(np.unique(em.elements[np.isin(em.elements[:, :4], flat).all(axis=1)]), top)
    contact = FrictionlessContact.of(ContactSurface.of(em, mesh.boundary_faces, prescribed), LAW.shear_modulus_Pa,
                                     ContactSettings(penetration_tol_mm=1e-5))
    system = Equilibrium.of(Solid.of(em, LAW), prescribed, top, 1e-9, held_z=np.arange(len(x)), contact=contact)
    cylinder = np.setdiff1d(np.arange(len(x)), prescribed)
    u0 = np.zeros_like(x)
    u0[top, 1] = -push_mm * MM
    u0[cylinder, 1] = -push_mm * MM * (1 + x[cylinder, 1] / (radius_mm * MM))
    result = newton_augmented(system, u0)
    assert result.status == "converged"
    line_load = -result.forces[top, 1].sum() / (thickness_mm * MM)  # N/m
    e_star = 10e6 / (1 - 0.45**2)
    a_hertz = np.sqrt(4 * line_load * radius_mm * MM / (np.pi * e_star))
    pairs = contact.pairs(result.u)
    p = contact.pressure_Pa(pairs)
    xq = contact.surface.points(result.u, pairs.point)[:, 0]
    fit = p > 0.2 * p.max()
    c0, c1 = np.linalg.lstsq(np.column_stack([np.ones(fit.sum()), xq[fit] ** 2]), p[fit] ** 2, rcond=None)[0]
    p0, a = np.sqrt(c0), np.sqrt(-c0 / c1)
    assert p.max() < 1.06 * p0  # a Gauss point's own pressure: within 5 % of the fit's peak (measured 4.6 %)
    return a / a_hertz - 1, p0 / (2 * line_load / (np.pi * a_hertz)) - 1


def test_hertz_a_cylinder_pressed_on_a_flat():
    # h = 0.05 mm, about 11 elements across the half-width a = 0.54 mm (a / R = 0.054); 7.4k tetrahedra
    width, peak = _hertz(0.05)
    assert abs(width) < 0.02 and abs(peak) < 0.02  # measured -1.24 % and +0.50 %


@pytest.mark.slow
def test_hertz_converges_on_refinement():
    coarse, fine = _hertz(0.05), _hertz(0.025)  # measured (-1.24 %, +0.50 %) then (-1.17 %, -0.20 %)
    assert abs(fine[0]) < abs(coarse[0]) and abs(fine[1]) < abs(coarse[1])


def _dense_tangent(system: Equilibrium, u: np.ndarray, geometric: bool) -> np.ndarray:
    """The free-node tangent at u as a dense matrix, column by column from `Equilibrium.tangent_product` (the
    element-wise product, not the assembly that `factor` uses); without the contact's geometric part unless
    `geometric`."""
    n = 3 * len(system.free)
    k = np.empty((n, n))
    for j in range(n):
        v = np.zeros_like(u)
        v[system.free] = np.eye(1, n, j).reshape(-1, 3)
        k[:, j] = system.residual(system.tangent_product(u, v))
    if not geometric:
        nodes, full = system.contact.tangent_blocks(u, True)
        _, normal = system.contact.tangent_blocks(u, False)
        rows = system.node_index[nodes]
        for p, a, b in zip(*np.nonzero((rows[:, :, None] >= 0) & (rows[:, None, :] >= 0))):
            i, j = 3 * rows[p, a], 3 * rows[p, b]
            k[i:i + 3, j:j + 3] -= full[p, a, b] - normal[p, a, b]
    return k


def test_a_state_is_stable_where_its_tangent_or_the_one_with_the_normal_stiffness_only_is_positive_definite(monkeypatch):
    """`Equilibrium.stable_factor`, against LAPACK's eigenvalues of the two tangents: at the pressed blocks' equilibrium
    the tangent is positive definite, and one factorization judges; with a pressure a hundred times the shear
    modulus the pressure's geometric part makes it indefinite (a crease), the tangent with the contact's normal
    stiffness only stays positive definite, and the state is stable, with the full tangent factored again for the
    path's direction; with the solid's tangent shifted below that one's smallest eigenvalue, both are indefinite
    and the state is not stable."""
    system, u0, *_ = _blocks(2, 2, False)  # the base deformable: its facets turn under the pressure
    u = newton_augmented(system, u0).u
    assert np.linalg.eigvalsh(_dense_tangent(system, u, True)).min() > 0
    before = system.factorizations
    assert system.stable_factor(u).inertia()[1] == 0 and system.factorizations == before + 1

    contact = system.contact
    keys = contact.assignment[0] * len(contact.surface.facets) + contact.assignment[1]
    contact.multipliers = Multipliers(keys, np.full(len(keys), 100 * LAW.shear_modulus_Pa))
    crease = _dense_tangent(system, u, True)
    full, normal = np.linalg.eigvalsh(crease), np.linalg.eigvalsh(_dense_tangent(system, u, False))
    assert full.min() < 0 < normal.min()
    before = system.factorizations
    factors = system.stable_factor(u)
    assert system.factorizations == before + 3 and factors.inertia()[1] == np.sum(full < 0)
    v = np.random.default_rng(1).normal(size=3 * len(system.free))
    assert np.linalg.norm(crease @ factors.solve(v) - v) < 1e-9 * np.linalg.norm(v)

    tangent, shift = Solid.tangent, 1.01 * normal.min()

    def shifted(solid, u, pattern):
        k = tangent(solid, u, pattern)
        k.values[k.rows == k.cols] -= shift * np.eye(3)
        return k

    monkeypatch.setattr(Solid, "tangent", shifted)
    with pytest.raises(NotPositiveDefinite):
        system.stable_factor(u)
