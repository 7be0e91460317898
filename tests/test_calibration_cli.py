"""The explain commands end to end: bench file, generic table, thesis example, real recordings."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest
from click.testing import CliRunner

from seadesign.cli import main
from seadesign.data import write_bench
from seadesign.constants import THESIS_K_MEASURED_NM_PER_RAD as K_MEASURED_NM_PER_RAD
from seadesign.calibration.thesis import K_FEA_NM_PER_RAD
from seadesign.twin import BenchProtocol, bench_effects, simulate_bench


def test_explain_bench_file_writes_report_json_and_calibration(tmp_path, spring_file, spring_dict):
    chain = bench_effects(9.106).configure("stiffness_scale", enabled=True, scale=0.75)
    table, meta = simulate_bench(spring_dict, BenchProtocol(frequency_hz=0.1, duration_s=40.0), effects=chain, seed=4)
    bench = write_bench(table, tmp_path / "bench.csv", meta)
    res = CliRunner().invoke(main, ["explain", str(bench), "--spring", str(spring_file), "--json",
                                    str(tmp_path / "r.json"), "-o", str(tmp_path / "out")])
    assert res.exit_code == 0, res.output
    report = json.loads((tmp_path / "r.json").read_text())
    assert report["final"]["effects"] == ["stiffness_scale"] and report["steps"] == []  # k is declared, refitted
    check = report["declared"][0]
    assert check["name"] == "stiffness_scale" and check["supported"] and "differs from the declared k" in check["text"]
    p = check["fitted"]["scale"]
    # measured: the scale 5.5e-5 off, the held-out RMSE 0.028 times the declared model's
    assert p["value"] == pytest.approx(0.75, rel=2e-4) and p["unit"] == "1" and p["uncertainty"] > 0
    assert report["final"]["errors"]["held_out"]["rmse"] < 0.085 * report["plain"]["errors"]["held_out"]["rmse"]
    assert "autocorrelation" in report["residual_tests"]
    cal = json.loads((tmp_path / "out" / "bench_calibration.json").read_text())
    assert cal["stiffness_scale"] == pytest.approx(0.75, rel=2e-4)
    assert cal["k_fitted_Nm_per_rad"] == pytest.approx(0.75 * 9.106, rel=2e-4)
    # the fitted law of the spring's material: every modulus times the scale (the spring was computed at the
    # material file's modulus), mu = 2 (C10 + C01), the bench file's hash
    import hashlib

    from seadesign.design.materials import load_material

    law, ninjaflex = cal["law"], load_material("ninjaflex").law
    assert cal["material"] == "ninjaflex" and law["model"] == ninjaflex.model
    assert law["c10_Pa"] == pytest.approx(cal["stiffness_scale"] * ninjaflex.c10_Pa, rel=1e-12)
    assert law["d1_per_Pa"] == pytest.approx(ninjaflex.d1_per_Pa / cal["stiffness_scale"], rel=1e-12)
    assert law["mu_Pa"] == pytest.approx(2 * (law["c10_Pa"] + law.get("c01_Pa", 0.0)), rel=1e-12)
    assert law["mu_uncertainty_Pa"] / law["mu_Pa"] == pytest.approx(p["uncertainty"] / p["value"], rel=1e-9)
    assert "anisotropic" in law["note"]
    assert cal["source_sha256"] == hashlib.sha256(bench.read_bytes()).hexdigest()
    html = (tmp_path / "out" / "bench.html").read_text()
    assert "data:image/png;base64," in html and (tmp_path / "out" / "bench_loop.png").exists()


def test_explain_generic_table_and_bad_column(tmp_path):
    rng = np.random.default_rng(0)
    t = np.arange(3000) / 50.0
    x = np.sin(2 * np.pi * 0.3 * t)
    df = pd.DataFrame({"t": t, "x": x, "pred": 2.0 * x, "meas": 2.0 * x + 0.5 + rng.normal(0, 0.01, t.size)})
    df.to_csv(tmp_path / "tab.csv", index=False)
    args = ["explain", str(tmp_path / "tab.csv"), "--measured", "meas", "--predicted", "pred",
            "--signal", "time=t", "--signal", "displacement=x", "--measured-unit", "N", "-o", str(tmp_path / "o")]
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 0, res.output
    assert "sensor_offset" in res.output
    bad = CliRunner().invoke(main, [*args[:5], "nope", *args[6:]])
    assert bad.exit_code != 0 and "predicted column 'nope'" in bad.output


@pytest.mark.parametrize("with_curve", [False, True])
def test_thesis_worked_example(tmp_path, spring_file, spring_dict, with_curve):
    """The worked case on a spring.json with k, and on one that carries its design's torque curve (the default
    sweep's): the thesis's FEA and bench were linear, so the curve plays no part."""
    if with_curve:
        from seadesign.design.spring import write_spring

        theta = np.linspace(0.0, 0.25, 6)
        curve = {"rotation_rad": theta.tolist(), "torque_Nm": (30.0 * theta * (1 - theta)).tolist(),
                 "source": "fea_large_deflection", "stop_reason": "bifurcation", "hard_stop": False}
        spring_file = write_spring({**spring_dict, "schema_version": 2, "torque_curve": curve}, tmp_path / "curve.json")
    res = CliRunner().invoke(main, ["explain-thesis", "--spring", str(spring_file), "-o", str(tmp_path)])
    assert res.exit_code == 0, res.output
    cal = json.loads((tmp_path / "thesis_calibration.json").read_text())
    assert set(cal["effects_found"]) == {"stiffness_scale", "dead_band"}
    # measured: the scale 3.8e-4 off, the dead-band 0.89 %, the held-out RMSE 1.1e-4 times the FEA k's
    assert cal["stiffness_scale"] == pytest.approx(K_MEASURED_NM_PER_RAD / K_FEA_NM_PER_RAD, rel=1.2e-3)
    assert cal["parameters"]["dead_band"]["width_rad"]["value"] == pytest.approx(0.03, rel=0.027)
    assert cal["held_out_rmse_after"] < 3.5e-4 * cal["held_out_rmse_before"]
    # the scale is relative to the thesis FEA's material (generic TPU), so the sweep takes the fitted modulus
    from seadesign.sweep.pipeline import apply_calibration
    from seadesign.design.materials import load_material
    from seadesign.design.study import load_study

    study, _ = apply_calibration(load_study("wolfgang_knee"), tmp_path / "thesis_calibration.json")
    e_thesis = load_material("generic_tpu").youngs_modulus_Pa
    assert study.material.youngs_modulus_Pa == pytest.approx(e_thesis * K_MEASURED_NM_PER_RAD / K_FEA_NM_PER_RAD, rel=1.2e-3)


def test_outputs_go_under_exports_by_default(tmp_path, monkeypatch, spring_file, spring_dict):
    """explain writes exports/explain/<file stem>/, explain-thesis exports/explain_thesis/, and the tutorial's
    `sweep --calibration exports/explain_thesis/thesis_calibration.json` path exists afterwards."""
    chain = bench_effects(9.106).configure("stiffness_scale", enabled=True, scale=0.8)
    table, meta = simulate_bench(spring_dict, BenchProtocol(frequency_hz=0.1, duration_s=20.0), effects=chain, seed=1)
    bench = write_bench(table, tmp_path / "in" / "mybench.csv", meta)
    monkeypatch.chdir(tmp_path)
    res = CliRunner().invoke(main, ["explain", str(bench), "--spring", str(spring_file)])
    assert res.exit_code == 0, res.output
    assert (tmp_path / "exports" / "explain" / "mybench" / "mybench.md").exists()
    assert (tmp_path / "exports" / "explain" / "mybench" / "mybench_calibration.json").exists()
    res = CliRunner().invoke(main, ["explain-thesis", "--spring", str(spring_file)])
    assert res.exit_code == 0, res.output
    assert (tmp_path / "exports" / "explain_thesis" / "thesis_calibration.json").exists()
    assert "sweep --calibration exports/explain_thesis/thesis_calibration.json" in res.output
