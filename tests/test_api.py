"""`import seadesign as sd`: light to import, and the same numbers as the command line for the same candidate of a
tiny study (the linear k, the torque path against the sweep's, the sweep's table), with tables and plots to look at."""

from __future__ import annotations

import json
import subprocess
import sys
import time

import numpy as np
import pandas as pd
import pytest
from click.testing import CliRunner

import seadesign as sd
from seadesign.cli import main
from seadesign.errors import ConfigError
from sweep_helpers import write_tiny_study


def test_import_is_light_and_every_name_resolves():
    code = ("import sys, seadesign; heavy = [m for m in ('torch', 'cadquery', 'pyvista', 'matplotlib', 'pandas', "
            "'scipy', 'gmsh') if m in sys.modules]; print(heavy)")
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert run.stdout.strip() == "[]"
    for name in sd.__all__:
        assert getattr(sd, name) is not None, name
    assert set(sd.__all__) <= set(dir(sd))
    with pytest.raises(AttributeError, match="no attribute 'sweep_everything'"):
        sd.sweep_everything  # noqa: B018


def test_the_report_only_writes_it_imports_neither_the_fea_nor_the_mesher():
    code = "import sys, seadesign.report; print(sorted({m.split('.')[1] for m in sys.modules if m.startswith('seadesign.')}))"
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert "'fea'" not in run.stdout and "'mesh'" not in run.stdout and "'report'" in run.stdout


@pytest.fixture(scope="module")
def tiny(tmp_path_factory):
    """(study, root, CLI sweep output folder, CLI output) after one CLI sweep of the tiny study."""
    root = tmp_path_factory.mktemp("api")
    path = write_tiny_study(root)
    result = CliRunner().invoke(main, ["sweep", str(path), "--jobs", "1", "--quiet", "--out", str(root / "cli"),
                                       "--cache-dir", str(root / "cache")])
    assert result.exit_code == 0, result.output
    return sd.load_study(path), root, root / "cli" / "tiny", result.output


def test_solve_gives_the_k_of_the_solve_command(tiny, tmp_path):
    study, _, _, _ = tiny
    result = CliRunner().invoke(main, ["solve", str(study.path), "--beams", "3", "--thickness-mm", "8",
                                       "--out", str(tmp_path / "cli")])
    assert result.exit_code == 0, result.output
    cli = json.loads((tmp_path / "cli" / "3beams_8mm.json").read_text())["results"]
    api = sd.solve(study, study.candidate(beam_count=3, beam_thickness_mm=8.0), out_dir=tmp_path / "api")
    assert api.k_Nm_per_rad == pytest.approx(cli["k_Nm_per_rad"], rel=1e-9)
    assert api.results["stall_von_mises_max_MPa"] == pytest.approx(cli["stall_von_mises_max_MPa"], rel=1e-9)
    assert [p.name for p in api.files] == ["3beams_8mm.json", "3beams_8mm.vtu"] and all(p.is_file() for p in api.files)


def test_torque_path_is_the_sweeps_path_from_the_default_cache(tiny, tmp_path, monkeypatch):
    """Solved afresh in an empty default cache ($SEADESIGN_CACHE), the path is the sweep's row's curve; the second
    call comes from that cache."""
    study, _, folder, _ = tiny
    monkeypatch.setenv("SEADESIGN_CACHE", str(tmp_path / "cache"))
    candidate = study.candidate(beam_count=3, beam_thickness_mm=8.0)
    path = sd.torque_path(study, candidate)
    assert any((tmp_path / "cache" / "path").rglob("*.pkl"))
    row = pd.read_parquet(folder / "results.parquet").set_index("candidate").loc[candidate.name]
    t = path.to_frame()
    assert list(t.columns) == ["rotation_rad", "rotation_deg", "torque_Nm", "tangent_Nm_per_rad"]
    np.testing.assert_allclose(t["rotation_rad"], row["large_curve_rotation_rad"], rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(t["torque_Nm"], row["large_curve_torque_Nm"], rtol=1e-9, atol=1e-12)
    assert path.stop_reason == row["large_stop_reason"]
    assert path.stop_torque_Nm == pytest.approx(row["large_stop_torque_Nm"], rel=1e-9)
    t0 = time.perf_counter()
    again = sd.torque_path(study, candidate)
    assert time.perf_counter() - t0 < 5.0 and again.to_frame().equals(t)
    ax = path.plot()
    drawn = ax.get_lines()[0]
    np.testing.assert_array_equal(drawn.get_xdata(), t["rotation_rad"])
    np.testing.assert_array_equal(drawn.get_ydata(), t["torque_Nm"])
    assert ax.get_xlabel() == "hub rotation (rad)" and ax.get_ylabel() == "torque (Nm)"


def test_sweep_study_gives_the_commands_table_and_choice(tiny, tmp_path):
    study, root, folder, printed = tiny
    result = sd.sweep_study(study, tmp_path, jobs=1, quiet=True, cache_dir=root / "cache")
    cli = pd.read_parquet(folder / "results.parquet")
    api = result.to_frame()
    assert api["candidate"].tolist() == cli["candidate"].tolist()
    np.testing.assert_allclose(api["k_Nm_per_rad"].astype(float), cli["k_Nm_per_rad"].astype(float), rtol=1e-12)
    assert api["status"].tolist() == cli["status"].tolist() and api["rank"].equals(cli["rank"])
    assert result.choice.explanation in printed and result.lines(quiet=True)[1] == result.choice.explanation
    assert (tmp_path / "tiny" / "spring.json").is_file()
    ax = result.plot()
    solved = api[api["status"] == "ok"]
    curves = [line for line in ax.get_lines() if line.get_label().startswith(tuple(solved["candidate"]))]
    assert len(curves) == len(solved)
    np.testing.assert_array_equal(curves[0].get_ydata(), solved.iloc[0]["large_curve_torque_Nm"])


def test_bad_candidates_are_named(tiny, tmp_path):
    study, _, _, _ = tiny
    with pytest.raises(ConfigError, match="beam_count = 4 is not in study 'tiny'"):
        study.candidate(beam_count=4, beam_thickness_mm=8.0)
    touching = study.candidate(beam_count=10, beam_thickness_mm=8.0)
    checked, _ = sd.geometry(study, touching)
    assert not checked.valid and "touch" in "; ".join(checked.reasons)
    for call in (lambda: sd.export(study, touching, tmp_path), lambda: sd.torque_path(study, touching),
                 lambda: sd.solve(study, touching)):
        with pytest.raises(ConfigError, match="candidate 10 beams x 8 mm is invalid: .*touch"):
            call()


def test_calibration_errors_name_the_key(tmp_path):
    (tmp_path / "c.json").write_text(json.dumps({"youngs_modulus_Pa": -1}))
    with pytest.raises(ConfigError, match="'youngs_modulus_Pa' must be a positive number"):
        sd.apply_calibration(sd.load_study(), tmp_path / "c.json")


def test_the_exploration_result_as_a_table_and_a_plot():
    """`ExplorationResult.to_frame` and `plot` on an evaluated table made here: the search's unit-cube columns
    dropped, the choice flagged, and each design drawn once in its series."""
    from types import SimpleNamespace

    import matplotlib

    matplotlib.use("Agg")
    from seadesign.explore.pipeline import ExplorationResult

    evaluated = pd.DataFrame({"x0": [0.1, 0.5, 0.9, 0.3], "x1": [0.2, 0.4, 0.6, 0.8], "candidate": list("abcd"),
                              "mass_g": [30.0, 25.0, 40.0, 35.0], "total_violation": [0.0, 0.2, 0.0, 0.5],
                              "front": [True, True, False, False], "x_offset_mm": [1.0, 2.0, 3.0, 4.0]})
    run = SimpleNamespace(exploration=SimpleNamespace(evaluated=evaluated), decision=SimpleNamespace(index=0),
                          problem=SimpleNamespace(objectives=("mass_g",)))
    result = ExplorationResult(SimpleNamespace(name="tiny"), run, None, {})
    t = result.to_frame()
    assert list(t.columns) == ["candidate", "mass_g", "total_violation", "front", "x_offset_mm", "chosen"]
    assert t["chosen"].tolist() == [True, False, False, False]
    assert "x0" in evaluated.columns  # a copy: the exploration's own table keeps its columns
    ax = result.plot()
    series = {line.get_label(): line.get_xydata().tolist() for line in ax.get_lines()}
    assert series == {"evaluated": [[40.0, 0.0], [35.0, 0.5]], "front": [[30.0, 0.0], [25.0, 0.2]],
                      "chosen": [[30.0, 0.0]]}
