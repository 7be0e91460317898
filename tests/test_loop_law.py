"""The material law fitted from a bench curve (`loop.law_family`): trial-law paths of the spring's own part, the
law's shape traced beside its scale, the fitted law in the calibration JSON and the refusals.

The independent reference is CalculiX: a bench curve written with NLGEOM and *HYPERELASTIC, MOONEY-RIVLIN (or
YEOH) with known constants on the spring's own path mesh, the hub driven as on the bench, then sampled as a bench
would (a 3-minute 100 Hz file, 12-bit angles, 0.02 Nm torque noise). The spring is one candidate of a small study
written here (a coarse mesh, so that our paths and CalculiX's take a minute)."""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from seadesign.design.materials import Hyperelastic

STUDY = "law_bench"
ANGLE_STEP_RAD = 2 * np.pi / 4096  # a 12-bit encoder
NOISE_NM = 0.02


@pytest.fixture(scope="module")
def bench_spring(tmp_path_factory):
    """A one-candidate study (6 beams x 8 mm, the default study's NinjaFlex part on a coarse mesh) swept to
    spring.json, in a folder that is the working directory of the module's tests (the study is found by name)."""
    from seadesign.sweep.pipeline import sweep_study

    folder = tmp_path_factory.mktemp("law")
    text = Path(__file__).parents[1].joinpath("studies", "wolfgang_knee.toml").read_text()
    text = re.sub(r'^name = .*$', f'name = "{STUDY}"', text, count=1, flags=re.M)
    text = re.sub(r"^beam_count = .*$", "beam_count = [6]", text, count=1, flags=re.M)
    text = re.sub(r"^beam_thickness_mm = .*$", "beam_thickness_mm = [8.0]", text, count=1, flags=re.M)
    text = re.sub(r"^elements_per_circle = .*$", "elements_per_circle = 8.0", text, count=1, flags=re.M)
    (folder / f"{STUDY}.toml").write_text(text)
    with pytest.MonkeyPatch.context() as mp:
        mp.chdir(folder)
        mp.setenv("SEADESIGN_CACHE", str(folder / "cache"))
        sweep_study(STUDY, folder / "exports", quiet=True, jobs=1)
    return folder, folder / "exports" / STUDY / "spring.json"


def _ccx_curve(folder: Path, law: Hyperelastic, end_rad: float, n: int = 10):
    """CalculiX's torque (Nm) at n rotations up to end_rad on the spring's path mesh, hub driven, ring held."""
    from seadesign.design.study import load_study
    from seadesign.fea.ccx import path_nodes, run_ccx_path, write_path_inp
    from seadesign.run.cache import Cache
    from seadesign.sweep.stages import SolverSettings, tetrahedralize

    study = load_study(folder / f"{STUDY}.toml")
    checked, part = study.check(study.candidates()[0])
    mesh = tetrahedralize(study, checked, part, Cache(folder / "cache"), layers=SolverSettings().path_layers)
    emesh, hub, ring = path_nodes(mesh)
    theta = list(np.linspace(end_rad / n, end_rad, n))
    cc = run_ccx_path(write_path_inp(folder / f"{law.model}.inp", emesh, hub, ring, law, theta), emesh.nodes_m, theta)
    assert cc.failure is None
    return np.concatenate([[0.0], cc.rotation_rad]), np.concatenate([[0.0], cc.torque_Nm])


def _bench_file(path: Path, rotation_rad, torque_Nm, reach_rad: float, seed: int = 0) -> Path:
    """A 3-minute 100 Hz bench file through the curve (PCHIP, odd): two slow sweeps to +-reach_rad, 12-bit
    angles, torque noise."""
    from scipy.interpolate import PchipInterpolator

    rng = np.random.default_rng(seed)
    t = np.arange(0.0, 180.0, 0.01)
    d = reach_rad * np.sin(2 * np.pi * t / 20.0) * (0.6 + 0.4 * np.sin(2 * np.pi * t / 67.0))
    curve = PchipInterpolator(rotation_rad, torque_Nm)
    tau = np.sign(d) * curve(np.abs(d)) + rng.normal(0.0, NOISE_NM, t.size)
    pd.DataFrame({"time_s": t, "torque_Nm": tau,
                  "deflection_rad": np.round(d / ANGLE_STEP_RAD) * ANGLE_STEP_RAD}).to_csv(path, index=False)
    return path


@pytest.mark.slow
def test_a_mooney_rivlin_bench_curve_from_calculix_is_fitted_as_its_law(bench_spring, ccx, monkeypatch):
    """A part at half the material's modulus with 60 % of it in C01: the loop names the Mooney-Rivlin shape,
    2 (C10 + C01) comes back within 2 % and C10 and C01 each within 3 reported uncertainties."""
    from seadesign.loop.explain_file import explain_file

    folder, spring_path = bench_spring
    monkeypatch.chdir(folder)
    monkeypatch.setenv("SEADESIGN_CACHE", str(folder / "cache"))
    spring = json.loads(spring_path.read_text())
    from seadesign.design.materials import load_material

    base = load_material("ninjaflex").law
    half_mu = 0.5 * base.shear_modulus_Pa / 2  # half the modulus
    true = Hyperelastic("mooney_rivlin", 0.4 * half_mu, 2 * base.d1_per_Pa, "test", c01_Pa=0.6 * half_mu)
    end = spring["torque_curve"]["rotation_rad"][-1]
    theta, torque = _ccx_curve(folder, true, end)
    bench = _bench_file(folder / "mr_bench.csv", theta, torque, 0.9 * end)
    found = explain_file(bench, spring_path, out_dir=folder / "mr")
    law = found.calibration["law"]
    assert "mooney_rivlin" in found.explanation.found, found.lines()
    assert law["model"] == "mooney_rivlin"
    assert law["mu_Pa"] == pytest.approx(true.shear_modulus_Pa, rel=0.02)
    for name in ("c10_Pa", "c01_Pa"):
        error = abs(law[name] - getattr(true, name)) / law[name.replace("_Pa", "_uncertainty_Pa")]
        assert error < 3.0, (name, law[name], getattr(true, name), error)
    assert law["correlation_c10_c01"] < -0.5  # the two trade off along mu
    assert "anisotropic" in law["note"]


@pytest.mark.slow
def test_a_yeoh_bench_curve_is_told_apart_or_said_to_be_indistinguishable(bench_spring, monkeypatch):
    """A Yeoh part (C20 / C10 = -0.07, half the modulus; its curve from our path, which agrees with CalculiX's
    YEOH to 2e-7 in test_fea_ccx_path): the report says which shape the held-out error prefers, or that over the
    file's strains the shapes cannot be told apart; the modulus comes back within 2 % either way. Measured: no
    shape is named (held-out RMSE with Yeoh within 1 % of the material's own law)."""
    from seadesign.design.materials import load_material
    from seadesign.loop.explain_file import explain_file
    from seadesign.loop.law_family import path_curve, spring_source

    folder, spring_path = bench_spring
    monkeypatch.chdir(folder)
    monkeypatch.setenv("SEADESIGN_CACHE", str(folder / "cache"))
    base = load_material("ninjaflex").law
    half_mu = 0.5 * base.shear_modulus_Pa / 2
    true = Hyperelastic("yeoh", half_mu, 2 * base.d1_per_Pa, "test", c20_Pa=-0.07 * half_mu)
    spring = json.loads(spring_path.read_text())
    curve = path_curve(spring_source(spring).with_law(true))
    end = spring["torque_curve"]["rotation_rad"][-1]
    found = explain_file(_bench_file(folder / "yeoh_bench.csv", curve.rotation_rad, curve.torque_Nm, 0.9 * end, seed=1),
                         spring_path, out_dir=folder / "yeoh")
    ex, verdict = found.explanation, found.explanation.verdict()
    named = [k for k in ex.found if k in ("yeoh", "mooney_rivlin")]
    if named == ["yeoh"]:
        assert "prefers the yeoh shape" in verdict or "cannot tell the yeoh and mooney_rivlin shapes apart" in verdict
    else:
        assert not named, verdict  # Mooney-Rivlin named alone would be wrong
        assert "the Mooney-Rivlin and Yeoh shapes and the material's law are indistinguishable" in verdict
        assert "shape_unsupported" in found.calibration["law"]
    assert found.calibration["law"]["mu_Pa"] == pytest.approx(true.shear_modulus_Pa, rel=0.02)
