"""`seadesign solve` on a study candidate: printed and written results, VTU fields, CalculiX decks,
and clean errors for bad input."""

from __future__ import annotations

import json
import numpy as np
import pytest
from click.testing import CliRunner

from seadesign.cli import main
from seadesign.design.study import load_study
from sweep_helpers import write_tiny_study


@pytest.fixture(scope="module")
def solved(tmp_path_factory):
    root = tmp_path_factory.mktemp("solve")
    study = write_tiny_study(root)
    out, ccx = root / "out", root / "ccx"
    result = CliRunner().invoke(main, ["solve", str(study), "--beams", "3", "--thickness-mm", "8",
                                       "--elements-per-circle", "0", "--out", str(out), "--export-ccx", str(ccx)])
    assert result.exit_code == 0, result.output
    return load_study(study), out, ccx, result.output


def test_results_are_printed_and_written_with_units(solved):
    study, out, _, printed = solved
    doc = json.loads((out / "3beams_8mm.json").read_text())
    r = doc["results"]
    assert r["equilibrium_rel_error"] < 1e-6
    assert r["stall_rotation_rad"] == pytest.approx(study.load_cases.stall_torque_Nm / r["k_Nm_per_rad"], rel=1e-9)
    assert f"{r['k_Nm_per_rad']:.5g} Nm/rad" in " ".join(printed.split())
    assert doc["mesh"]["target_edge_mm"] == pytest.approx(8.0 / 0.6)  # the tiny study's 0.6 across 8 mm


def test_vtu_hub_bolt_walls_move_as_one_rigid_body_at_the_printed_rotation(solved):
    import pyvista as pv

    study, out, _, _ = solved
    r = json.loads((out / "3beams_8mm.json").read_text())["results"]
    grid = pv.read(out / "3beams_8mm.vtu")
    x = np.asarray(grid.points)  # mm
    u = np.asarray(grid.point_data["stall_displacement_mm"])
    holes = study.candidate(3, 8.0).params.interfaces().hub_holes
    centres = np.array([[h.x_mm, h.y_mm] for h in holes])
    dist = np.min(np.linalg.norm(x[:, None, :2] - centres[None], axis=2), axis=1)
    wall = np.abs(dist - holes[0].radius_mm) < 1e-6
    assert wall.sum() > 50
    # least-squares rigid motion u = a + w x x of the wall nodes: it must fit exactly
    xw, uw = x[wall], u[wall]
    rows = []
    for px, py, pz in xw:
        rows += [[1, 0, 0, 0, pz, -py], [0, 1, 0, -pz, 0, px], [0, 0, 1, py, -px, 0]]
    sol, *_ = np.linalg.lstsq(np.array(rows, float), uw.ravel(), rcond=None)
    fit = np.array(rows, float) @ sol
    assert np.abs(fit - uw.ravel()).max() < 1e-6 * np.abs(uw).max()
    assert abs(sol[5]) == pytest.approx(r["stall_rotation_rad"], rel=1e-6)


def test_calculix_decks_name_the_coupled_node_sets(solved):
    _, _, ccx, _ = solved
    for case in ("stall", "impact"):
        text = (ccx / f"{case}.inp").read_text().upper()
        assert "*RIGID BODY" in text and "C3D10" in text and "*STATIC" in text


@pytest.mark.parametrize("args, message", [
    (["--beams", "3"], "needs --beams N and --thickness-mm T"),
    (["--beams", "10", "--thickness-mm", "8"], "invalid"),
])
def test_bad_candidates_get_a_clean_error(tmp_path, args, message):
    study = write_tiny_study(tmp_path)
    result = CliRunner().invoke(main, ["solve", str(study), *args, "--out", str(tmp_path / "o")])
    assert result.exit_code == 2 and message in result.output and "Traceback" not in result.output
