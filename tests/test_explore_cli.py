"""`seadesign explore` on a tiny study: invalid geometry is screened out (counted apart from the full-path
evaluations), every reported design was solved, the outputs are written, a rerun reuses every stored
evaluation, and the report opens in a browser with the decision first."""

from __future__ import annotations

import json
import re

import pandas as pd
import pytest
from click.testing import CliRunner

from helpers_browser import assert_readable
from seadesign.cli import main
from seadesign.design.spring import load_spring
from sweep_helpers import write_tiny_study


@pytest.mark.slow  # 49 s at a load average of 6 (one full path, the report, a rerun)
def test_explore_command(tmp_path):
    study = write_tiny_study(tmp_path, name="tinyx")  # 3 beams x 8 mm builds; 10 beams x 8 mm does not
    args = ["explore", str(study), "--budget", "2", "--jobs", "1", "--quiet", "--out", str(tmp_path / "out"),
            "--cache-dir", str(tmp_path / "cache")]
    result = CliRunner().invoke(main, args)
    assert result.exit_code == 0, result.output
    assert "1 full-path evaluations, 2 screenings (1 invalid)" in result.output
    folder = tmp_path / "out" / "tinyx"
    t = pd.read_csv(folder / "results.csv")
    assert t["candidate"].tolist() == ["3 beams x 8 mm"] and (t["status"] == "ok").all()
    screened = pd.read_csv(folder / "screened.csv")
    assert screened["valid"].tolist() == [True, False] and "touch" in screened.loc[1, "reason"]
    # 3 x 8 mm stops at contact below the stall torque: nothing is feasible, and the report says what it misses
    assert not t["feasible"].any() and "carries the stall torque" in t.loc[0, "failed_constraints"]
    spring = load_spring(folder / "spring.json")
    assert spring["design"]["beam_count"] == 3 and spring["selection"]["meets_requirements"] is False
    # the evaluations skip k's error estimate (the stored evaluation row has none); the reported design gets it (0
    # here: the tiny study's coarsened mesh comes out the same as its mesh)
    stored = [json.loads(p.read_text()) for p in (folder / "rows").glob("*.json")]
    assert [pd.isna(r["k_rel_error"]) for r in stored if r.get("k_Nm_per_rad")] == [True]
    assert 0 <= t.loc[0, "k_rel_error"] < 0.05 and spring["k_rel_error"] == pytest.approx(t.loc[0, "k_rel_error"])
    assert t.loc[0, "k_coarse_Nm_per_rad"] > 0
    for name in ("front.csv", "surrogate_loo.csv", "sobol.csv", "parallel_coordinates.png", "history.png",
                 "torque_curves.png", "3beams_8mm.stl", "3beams_8mm.step", "report.md"):
        assert (folder / name).is_file(), name
    settings = json.loads((folder / "settings.json").read_text())
    assert settings["explorer"]["budget"] == 2 and settings["solver"]["k_error_estimate"] == "the reported design only"
    assert f"study {study} (sha256 {settings['files']['study']['sha256']})" in (folder / "report.md").read_text()
    seen = assert_readable(folder / "report.html")
    assert seen["decision"]["text"].startswith("No solved design meets every requirement. The nearest, 3 beams x 8 mm")
    rerun = CliRunner().invoke(main, args)  # every evaluation and screening comes back from the stored rows
    assert rerun.exit_code == 0 and pd.read_csv(folder / "results.csv").equals(t)
    # calibrated: NinjaFlex's law at half its moduli; k halves exactly (linear elasticity), outputs apart
    from seadesign.design.materials import load_material

    law = load_material("ninjaflex").law
    calibration = tmp_path / "calibration.json"
    calibration.write_text(json.dumps({"material": "ninjaflex", "law": {"model": law.model,
                                                                         "mu_Pa": 0.5 * law.shear_modulus_Pa}}))
    result = CliRunner().invoke(main, [*args, "--calibration", str(calibration)])
    assert result.exit_code == 0, result.output
    assert "calibrated from calibration.json: mu = " in result.output and "x 0.5 on every modulus of 'ninjaflex'" in \
        result.output
    calibrated = pd.read_csv(tmp_path / "out" / "tinyx-calibrated" / "results.csv")
    assert calibrated.loc[0, "k_Nm_per_rad"] == pytest.approx(0.5 * t.loc[0, "k_Nm_per_rad"], rel=1e-9)
    # the uncalibrated choice evaluated again with the calibrated material, beside the calibrated choice
    assert "calibration: the choice without and with it, each judged with the calibrated material:" in result.output
    old = re.search(r"uncalibrated choice, calibrated material: 3 beams x 8 mm: misses (.*)", result.output).group(1)
    new = re.search(r"  calibrated choice: 3 beams x 8 mm: misses (.*)", result.output).group(1)
    assert old == new == calibrated.loc[0, "failed_constraints"]  # the same design judged alike both ways


@pytest.mark.slow  # two explorations of one full path each
def test_explore_on_a_dask_cluster_verifies_the_same_designs(tmp_path, monkeypatch):
    pytest.importorskip("distributed")
    from seadesign.run import executors

    on_dask = []  # the tasks handed to Dask: the dask run must not fall back to local processes
    run_dask = executors.run_dask
    monkeypatch.setattr(executors, "run_dask", lambda fn, tasks, *a: on_dask.extend(tasks) or run_dask(fn, tasks, *a))
    study = write_tiny_study(tmp_path, name="tinyx")
    tables = {}
    for executor in ("local", "dask"):
        out = tmp_path / executor
        result = CliRunner().invoke(main, ["explore", str(study), "--budget", "2", "--jobs", "2", "--batch", "1",
                                           "--executor", executor, "--quiet", "--out", str(out),
                                           "--cache-dir", str(tmp_path / f"cache-{executor}")])
        assert result.exit_code == 0, result.output
        assert bool(on_dask) == (executor == "dask"), executor
        tables[executor] = pd.read_csv(out / "tinyx" / "results.csv")
    local, dask = tables["local"], tables["dask"]
    assert dask["candidate"].tolist() == local["candidate"].tolist() == ["3 beams x 8 mm"]
    # the same mesh and solves on a Dask worker: the numbers agree to round-off
    for col in ("k_Nm_per_rad", "large_stop_rotation_rad", "large_stop_torque_Nm"):
        assert dask.loc[0, col] == pytest.approx(local.loc[0, col], rel=1e-9), col
