"""Independent solver for the large-deflection path: CalculiX NLGEOM (C3D10, *HYPERELASTIC: NEO HOOKE, MOONEY-RIVLIN, YEOH)
on the same mesh, the same hub nodes driven to x' = R(theta) x and the same ring nodes held, against
`rotation_path` (formulation "full", CalculiX's) at the rotations of the path's own points."""

from __future__ import annotations

import numpy as np
import pytest
from helpers_annulus import annulus_mesh

from seadesign.design.materials import Hyperelastic
from seadesign.fea.ccx import PathIncrements, path_nodes, run_ccx_path, write_path_inp
from seadesign.fea.rotation_path import PathSettings, TorquePath, rotation_path

LAW = Hyperelastic.from_linear(12e6, 0.48)
# The .dat prints forces and displacements to 7 digits: measured differences 5.6e-8 (annulus),
# 5.1e-8 and 7.2e-8 (the two study candidates); tolerance about three times the largest.
RTOL = 2e-7


def _ccx_difference(tmp_path, mesh, law: Hyperelastic, path: TorquePath, beyond_rad: float = 0.0) -> np.ndarray:
    """|T_ccx / T_ours - 1| at every point of the path after rest (CalculiX must converge them all).
    With `beyond_rad`, CalculiX also takes one step that far past the path's last point, and must stop
    in it within two of the path's location tolerances of that point (where the path lost stability)."""
    points = path.points[1:]
    theta = [p.rotation_rad for p in points]
    emesh, hub, ring = path_nodes(mesh)
    steps = theta + [theta[-1] + beyond_rad] if beyond_rad else theta
    cc = run_ccx_path(write_path_inp(tmp_path / "path.inp", emesh, hub, ring, law, steps), emesh.nodes_m, steps)
    np.testing.assert_array_equal(cc.rotation_rad, theta)
    if beyond_rad:
        assert "increment size smaller than minimum" in cc.failure
        assert 0.0 <= cc.reached_rad - theta[-1] < 2 * PathSettings().locate_tol_rad
    else:
        assert cc.failure is None
    return np.abs(cc.torque_Nm / np.array([p.torque_Nm for p in points]) - 1.0)


#: the laws a calibration fits (`loop.law_family`), at NinjaFlex's initial shear modulus and compressibility
HALF_MU = LAW.c10_Pa
LAWS = {"neo_hooke": LAW,
        "mooney_rivlin": Hyperelastic("mooney_rivlin", 0.6 * HALF_MU, LAW.d1_per_Pa, "test", c01_Pa=0.4 * HALF_MU),
        "yeoh": Hyperelastic("yeoh", HALF_MU, LAW.d1_per_Pa, "test", c20_Pa=-0.1 * HALF_MU)}


@pytest.mark.parametrize("model", list(LAWS))
def test_calculix_nlgeom_agrees_on_an_annulus_to_half_a_radian(tmp_path, ccx, model):
    """Each law as CalculiX's *HYPERELASTIC card (NEO HOOKE, MOONEY-RIVLIN, YEOH) on the same annulus."""
    mesh = annulus_mesh(5.0, 12.0, 3.0, n_r=3, n_theta=16, n_z=2)
    path = rotation_path(mesh, LAWS[model], 100.0, PathSettings(max_rotation_rad=0.5))
    assert path.stop_reason == "rotation_limit"
    # the curve is nonlinear there: the secant at 0.5 rad is 3.1 % below the tangent at rest (measured, neo-Hooke)
    assert path.points[-1].torque_Nm / (0.5 * path.points[0].tangent_Nm_per_rad) < 0.98
    assert _ccx_difference(tmp_path, mesh, LAWS[model], path).max() < RTOL  # measured 5.6e-8 (neo-Hooke)


@pytest.mark.slow
@pytest.mark.parametrize("beams, thickness_mm, max_step_rad, stop", [(3, 8.0, 0.1, "contact"), (6, 6.0, 0.004, "bifurcation")])
def test_calculix_nlgeom_agrees_on_study_candidates(tmp_path, ccx, beams, thickness_mm, max_step_rad, stop):
    """Default-study candidates on a 4x coarser mesh (4-5k tets), to the stall torque or where the path
    stops (no strain limit: the comparison goes past it). 3 x 8 stops at contact past 0.3 rad. 6 x 6 loses
    stability at 0.257 rad on this mesh, and CalculiX cannot pass that rotation either, on any increments
    (measured: it stops at 0.25736 rad with increments of 2e-6 rad). The path finds the instability only
    with steps of at most 4 mrad: with 10 mrad steps or the default ones it steps over it to stable states
    past it and stops at contact near 0.32 rad (measured), so this check takes small steps. Ours 51 / 18 s,
    CalculiX 68 / 151 s on 2 cores."""
    from seadesign.design.study import load_study
    from seadesign.run.cache import Cache
    from seadesign.sweep.stages import tetrahedralize

    study = load_study()
    checked, part = study.check(study.candidate(beam_count=beams, beam_thickness_mm=thickness_mm))
    mesh = tetrahedralize(study, checked, part, Cache(tmp_path / "cache"), coarsening=4.0)
    law = study.material.law
    settings = PathSettings(max_rotation_rad=0.4, max_step_rad=max_step_rad)
    path = rotation_path(mesh, law, study.load_cases.stall_torque_Nm, settings)
    assert path.stop_reason == stop
    if stop == "contact":
        assert path.points[-1].rotation_rad > 0.3
        assert _ccx_difference(tmp_path, mesh, law, path).max() < RTOL  # measured 5.1e-8
    else:
        assert 0.25 < path.points[-1].rotation_rad < 0.26
        assert _ccx_difference(tmp_path, mesh, law, path, beyond_rad=0.01).max() < RTOL  # measured 7.2e-8


def test_a_step_calculix_does_not_converge_is_named_and_left_out(tmp_path, ccx):
    # 4 rad in one step with increments of at least 0.3 rad: ccx gives up on the second step
    mesh = annulus_mesh(5.0, 12.0, 3.0, n_r=3, n_theta=16, n_z=2)
    emesh, hub, ring = path_nodes(mesh)
    theta = [0.1, 4.0, 4.1]
    inp = write_path_inp(tmp_path / "path.inp", emesh, hub, ring, LAW, theta, PathIncrements(max_rad=4.0, min_rad=0.3))
    cc = run_ccx_path(inp, emesh.nodes_m, theta)
    assert "increment size smaller than minimum" in cc.failure and "4 rad" in cc.failure
    np.testing.assert_array_equal(cc.rotation_rad, [0.1])
    ours = rotation_path(mesh, LAW, 100.0, PathSettings(max_rotation_rad=0.1)).points[-1]
    assert ours.rotation_rad == 0.1 and cc.torque_Nm == pytest.approx([ours.torque_Nm], rel=RTOL)


@pytest.mark.default_mesh
def test_calculix_nlgeom_agrees_on_the_default_mesh(tmp_path, ccx):
    """3 beams x 6 mm, the smallest of the default study's result meshes (56k tets, 267k degrees of freedom,
    about the 257k of our first CalculiX NLGEOM check, on the 4 beams x 8 mm stall deck that
    `seadesign solve --export-ccx` writes), to 0.1 rad, where the secant is 2.9 % below the tangent at rest. Measured: 3.2e-9 to 1.6e-8 apart at the path's 4 rotations; 9 min 34 s with a sweep running beside
    it, CalculiX 15 iterations in 4 increments. Too long for CI (`-m default_mesh`)."""
    from seadesign.design.study import load_study
    from seadesign.run.cache import Cache
    from seadesign.sweep.stages import tetrahedralize

    study = load_study()
    checked, part = study.check(study.candidate(beam_count=3, beam_thickness_mm=6.0))
    mesh = tetrahedralize(study, checked, part, Cache(tmp_path / "cache"))
    path = rotation_path(mesh, study.material.law, study.load_cases.stall_torque_Nm, PathSettings(max_rotation_rad=0.1))
    assert path.stop_reason == "rotation_limit"
    assert _ccx_difference(tmp_path, mesh, study.material.law, path).max() < RTOL


def _through_contact(tmp_path, beams: int, thickness_mm: float, end_rad: float, max_step_rad: float = 0.1):
    """Our path through self-contact on a default-study candidate (4x coarser one-layer mesh) to `end_rad` in steps of
    at most `max_step_rad`, and
    CalculiX's on the same mesh with a face-to-face penalty contact pair (ten times our penalty) between the faces
    within 1.5 mm of where our contact touches at the end; CalculiX's torques at our points."""
    from seadesign.design.study import load_study
    from seadesign.fea.ccx_contact import pair_around
    from seadesign.fea.contact import ContactSettings
    from seadesign.fea.rotation_path import path_problem
    from seadesign.run.cache import Cache
    from seadesign.sweep.stages import tetrahedralize

    study = load_study()
    checked, part = study.check(study.candidate(beam_count=beams, beam_thickness_mm=thickness_mm))
    mesh = tetrahedralize(study, checked, part, Cache(tmp_path / "cache"), coarsening=4.0, layers=1)
    law = study.material.law
    settings = PathSettings(max_rotation_rad=end_rad, max_step_rad=max_step_rad, contact=ContactSettings())
    path = rotation_path(mesh, law, study.load_cases.impact_torque_Nm, settings)
    contact = path_problem(mesh, law, settings).system.contact
    deck = pair_around(contact, path.displacement_m, 1.5, 10 * contact.penalty_Pa_per_m)
    theta = [p.rotation_rad for p in path.points[1:]]
    emesh, hub, ring = path_nodes(mesh)
    inp = write_path_inp(tmp_path / "contact.inp", emesh, hub, ring, law, theta, PathIncrements(max_rad=0.02), deck)
    return path, run_ccx_path(inp, emesh.nodes_m, theta)


@pytest.mark.slow
@pytest.mark.parametrize("beams, thickness_mm, end_rad, max_step_rad", [(3, 8.0, 0.42, 0.1), (6, 8.0, 0.40, 0.01)])
def test_calculix_contact_pair_agrees_through_contact(tmp_path, ccx, beams, thickness_mm, end_rad, max_step_rad):
    """Two default-study candidates through contact, to `end_rad` or to where either solver stops, on their coarse
    meshes. Before contact CalculiX's contact pair stays open and the torques agree as without contact (measured at
    most 3.1e-8; CalculiX's face-to-face contact starts to push up to 0.02 rad before our first pressure: 1.3e-4 on
    6 x 8 mm at 0.28 rad); through contact they agree within 5.3e-4 (the issue asks 1 %). Measured 2026-11-29:
    - 3 x 8 mm: first contact 0.302 rad, the ring notch's root; to 0.42 rad, where contact carries 0.46 of the
      5.69 Nm (8 %); 8.4e-5 to 5.3e-4. Ours 21 s, CalculiX 69 s on 2 cores beside a sweep.
    - 6 x 8 mm, the default study's nearest design, in 10 mrad steps (with the default steps our path takes one
      step from 0.31 to 0.36 rad, and CalculiX stops in the crease at 0.3475 rad, leaving one point in contact):
      first contact 0.279 rad, the hub notch's root; our path ends unconverged at 0.340 rad
      (`contact_unconverged`), CalculiX follows it there; 2.5e-4 to 4.1e-4 through contact, where contact carries
      up to 3.8 % of the torque. Ours 71 s, CalculiX 171 s beside a sweep."""
    path, cc = _through_contact(tmp_path, beams, thickness_mm, end_rad, max_step_rad)
    first = path.events[0]
    assert first.kind == "contact"
    # compared to where either solver stops: CalculiX may stop in a crease, never before our first contact
    assert len(cc.rotation_rad) == len(path.points) - 1 or cc.reached_rad > first.rotation_rad
    ours = np.array([p.torque_Nm for p in path.points[1 : 1 + len(cc.rotation_rad)]])
    difference = np.abs(cc.torque_Nm / ours - 1.0)
    assert (cc.rotation_rad >= first.rotation_rad).sum() >= 2  # points in contact to compare
    assert difference[cc.rotation_rad < first.rotation_rad - 0.04].max() < RTOL
    assert difference.max() < 1e-3


def test_a_node_to_surface_pair_leaves_the_nodes_it_shares_with_the_master_out_of_the_slave():
    """One C3D10 (nodes 0-3 corners, 4-9 midsides of edges 01, 12, 20, 03, 13, 23): slave face S1 (0, 1, 2) and master
    face S2 (0, 3, 1) share the edge 0-1 with its midside 4, as a notch's two flanks share its root. The node-to-surface
    slave is S1's other nodes, 2 and the midsides 5 and 6 (1-based in the deck: 3, 6, 7); the master stays a face."""
    from seadesign.fea.ccx_contact import ContactPairDeck

    element = np.arange(10)[None, :]
    slave, master = np.array([[0, 1, 2]]), np.array([[1, 0, 3]])
    card = ContactPairDeck(slave, master, 3e11, 0.5, 3e11, node_to_surface=True).card(element).splitlines()
    at = card.index("*SURFACE, NAME=SLAVE, TYPE=NODE")
    assert card[at + 1 : at + 4] == ["3", "6", "7"] and card[at + 4] == "*SURFACE, NAME=MASTER, TYPE=ELEMENT"
    assert card[at + 5] == "1, S2"
    assert "*CONTACT PAIR, INTERACTION=TOUCH, TYPE=NODE TO SURFACE" in card and "*FRICTION" in card
    face_to_face = ContactPairDeck(slave, master, 3e11).card(element).splitlines()
    assert "1, S1" in face_to_face and "*CONTACT PAIR, INTERACTION=TOUCH, TYPE=SURFACE TO SURFACE" in face_to_face


def test_the_path_deck_leaves_the_field_controls_to_calculix_when_asked_and_writes_the_time_controls(tmp_path):
    """`PathIncrements(residual_rtol=None, time_controls=...)`: no *CONTROLS, PARAMETERS=FIELD card (ccx's default
    tolerance) and the time incrementation line in every step; by default the tight FIELD card and no time line."""
    mesh = annulus_mesh(5.0, 12.0, 3.0, n_r=1, n_theta=8, n_z=1)
    emesh, hub, ring = path_nodes(mesh)
    theta = [0.01, 0.02]
    loose = write_path_inp(tmp_path / "loose.inp", emesh, hub, ring, LAW, theta,
                           PathIncrements(residual_rtol=None, time_controls="8,10,9,30,10,4,,10")).read_text()
    assert "PARAMETERS=FIELD" not in loose
    assert loose.count("*CONTROLS, PARAMETERS=TIME INCREMENTATION\n8,10,9,30,10,4,,10\n") == len(theta)
    tight = write_path_inp(tmp_path / "tight.inp", emesh, hub, ring, LAW, theta, PathIncrements()).read_text()
    assert tight.count("*CONTROLS, PARAMETERS=FIELD\n1.000e-07, , , , 1.000e-07\n") == len(theta)
    assert "TIME INCREMENTATION" not in tight
