"""Independent solver: CalculiX (C3D10, *RIGID BODY) on the same mesh and boundary conditions."""

from __future__ import annotations

import numpy as np
import pytest
from helpers_parts import holed_annulus

from seadesign.fea.ccx import run_ccx, write_load_case_decks
from seadesign.fea.loadcases import analyse
from seadesign.mesh import mesh_part

E, NU, T_STALL, T_IMPACT = 12e6, 0.48, 2.0, 5.0


def test_calculix_agrees_on_both_load_cases(tmp_path, ccx):
    """Measured: k 1.0e-7, displacement field 4e-7 of its peak, reactions 1e-8 / 4e-8 (the .dat's
    printed digits); tolerances are five times that."""
    solid, ifc = holed_annulus()
    mesh = mesh_part(solid, ifc, elements_across_beam=1, beam_width_mm=3.0, cache_dir=tmp_path)
    a = analyse(mesh, E, NU, 4e6, T_STALL, T_IMPACT, bearing_radius_mm=9.0)
    decks = write_load_case_decks(tmp_path / "ccx", a.unit, E, NU, T_STALL, T_IMPACT)
    n = len(a.unit.emesh.nodes_m)

    stall = run_ccx(decks["stall"], n)
    assert T_STALL / stall.rotation_rad == pytest.approx(a.results.columns()["k_Nm_per_rad"], rel=5e-7)
    u = a.displacement_m("stall")
    assert np.abs(stall.displacement_m - u).max() < 2e-6 * np.abs(u).max()

    impact = run_ccx(decks["impact"], n)  # hub held, torque on the ring
    assert T_IMPACT / impact.rotation_rad == pytest.approx(a.results.columns()["k_Nm_per_rad"], rel=5e-7)
    u = a.displacement_m("impact")
    assert np.abs(impact.displacement_m - u).max() < 2e-6 * np.abs(u).max()
    # reactions per hub bolt and the peak nodal reaction
    node_force = dict(zip(impact.held_nodes, impact.reaction_N))
    per_bolt = [np.linalg.norm(sum(node_force[i] for i in nodes)) for nodes in a.unit.hub_groups.values()]
    assert max(per_bolt) == pytest.approx(a.results.columns()["impact_reaction_per_bolt_N"], rel=1e-7)
    peak = max(np.linalg.norm(node_force[i]) for nodes in a.unit.hub_groups.values() for i in nodes)
    assert peak == pytest.approx(a.results.columns()["impact_peak_nodal_reaction_N"], rel=2e-7)
