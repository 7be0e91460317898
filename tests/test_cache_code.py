"""Cached results are keyed on the code that made them: after a change to the solver's source,
a rerun recomputes the FEA rows and reuses the geometry (a copy of the package is edited and run
in a fresh process, as a developer would)."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pandas as pd
import pytest

from seadesign.run.fingerprint import code_fingerprint, project_imports
from sweep_helpers import write_tiny_study

REPO = Path(__file__).resolve().parents[1]


def _sweep(src: Path, study: Path, out: Path, cache: Path) -> dict:
    env = dict(os.environ, PYTHONPATH=str(src))
    cmd = [sys.executable, "-c", "from seadesign.cli import main; main()", "sweep", str(study), "--jobs", "1",
           "--quiet", "--out", str(out), "--cache-dir", str(cache)]
    proc = subprocess.run(cmd, env=env, cwd=src, capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    table = pd.read_csv(out / "tiny" / "results.csv")
    return {r["candidate"]: r for r in table.to_dict("records")}


def _entries(cache: Path, stage: str) -> set[Path]:
    return set((cache / stage).rglob("*.pkl"))


@pytest.mark.slow
def test_a_solver_change_recomputes_the_fea_and_reuses_the_geometry(tmp_path):
    src = tmp_path / "src"
    for folder in ("seadesign", "studies", "materials"):
        shutil.copytree(REPO / folder, src / folder, ignore=shutil.ignore_patterns("__pycache__"))
    study = write_tiny_study(tmp_path)
    cache = tmp_path / "cache"
    before = _sweep(src, study, tmp_path / "out1", cache)
    geometry, meshes, fea = _entries(cache, "geometry"), _entries(cache, "tetmesh"), _entries(cache, "fea")
    assert len(geometry) == 2 and len(fea) == 1 and meshes

    # the solver now applies 2 Nm where it says 1 Nm: every k halves if it is recomputed
    torsion = src / "seadesign" / "fea" / "torsion.py"
    text = torsion.read_text()
    assert text.count("rhs[self.coupling.ref_dofs[5]] = 1.0") == 1
    torsion.write_text(text.replace("rhs[self.coupling.ref_dofs[5]] = 1.0", "rhs[self.coupling.ref_dofs[5]] = 2.0"))
    after = _sweep(src, study, tmp_path / "out1", cache)

    assert _entries(cache, "geometry") == geometry  # geometry verdicts reused
    assert _entries(cache, "tetmesh") == meshes  # meshes reused
    assert len(_entries(cache, "fea") - fea) == 1  # the FEA solved again
    name = next(n for n, r in before.items() if r["status"] == "ok")
    assert after[name]["k_Nm_per_rad"] == pytest.approx(before[name]["k_Nm_per_rad"] / 2, rel=1e-9)


def test_fingerprint_follows_imports_inside_functions_and_parent_packages():
    # check_candidate imports the CAD code inside the function: it is part of the geometry's fingerprint
    source = (REPO / "seadesign" / "design" / "candidate.py").read_bytes()
    found = project_imports("seadesign.design.candidate", source)
    assert {"seadesign.design.geometry", "seadesign.design.validity", "seadesign.design"} <= found
    assert code_fingerprint("seadesign.design.candidate") != code_fingerprint("seadesign.design.geometry")
    with pytest.raises(ValueError, match="not a module"):
        code_fingerprint("seadesign.no_such_module")


def test_a_stored_row_is_keyed_on_the_code_that_builds_its_columns(tmp_path, monkeypatch):
    # the row's derived columns (k's error estimate, rotations in degrees, ...) come from sweep/table.py:
    # editing it must give new row keys, while the geometry stage's key stays
    from seadesign.design.study import load_study
    from seadesign.run import fingerprint
    from seadesign.sweep.runner import row_key
    from seadesign.sweep.stages import SolverSettings, geometry_key

    study = load_study(write_tiny_study(tmp_path))
    cand, settings = study.candidates()[0], SolverSettings()
    before = row_key(study, cand, settings), geometry_key(study, cand)
    table = fingerprint.module_path("seadesign.sweep.table")
    real = Path.read_bytes
    monkeypatch.setattr(Path, "read_bytes", lambda p: real(p) + (b"\n# edited\n" if p == table else b""))
    fingerprint.code_fingerprint.cache_clear()
    try:
        after = row_key(study, cand, settings), geometry_key(study, cand)
    finally:
        monkeypatch.undo()
        fingerprint.code_fingerprint.cache_clear()
    assert after[0] != before[0]
    assert after[1] == before[1]


def test_one_cache_root_and_the_retired_variable_is_named(tmp_path, monkeypatch):
    """Stages and meshes share $SEADESIGN_CACHE; the meshes' former variable is refused with the one to set."""
    from seadesign.errors import ConfigError
    from seadesign.run.cache import Cache, default_cache

    monkeypatch.delenv("SEADESIGN_CACHE_DIR", raising=False)
    monkeypatch.setenv("SEADESIGN_CACHE", str(tmp_path / "root"))
    assert default_cache().root == Cache().root == tmp_path / "root"
    monkeypatch.setenv("SEADESIGN_CACHE_DIR", str(tmp_path / "old"))
    with pytest.raises(ConfigError, match=f"SEADESIGN_CACHE_DIR={tmp_path / 'old'} is no longer read.*"
                                          f"Set SEADESIGN_CACHE={tmp_path / 'old'}"):
        default_cache()
    assert default_cache(tmp_path / "given").root == tmp_path / "given"  # an explicit root needs no variable
