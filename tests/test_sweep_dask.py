"""The sweep on a Dask LocalCluster gives the same rows as in-process, FEA included."""

from __future__ import annotations

import pytest

from seadesign.design.study import load_study
from seadesign.run.cache import Cache
from seadesign.run.progress import ProgressDisplay
from seadesign.sweep.runner import run_sweep
from sweep_helpers import write_tiny_study

pytest.importorskip("distributed")


@pytest.mark.slow  # about 45 s: a local cluster's start and a sweep on it
def test_dask_local_cluster_matches_serial_and_reports_stages(tmp_path, monkeypatch):
    # one valid candidate (meshed and solved on a Dask worker) and one invalid one
    study = load_study(write_tiny_study(tmp_path, beam_count="[3, 10]", beam_thickness_mm="[8.0]"))
    serial = run_sweep(study, tmp_path / "serial", cache=Cache(tmp_path / "c"), executor="serial", quiet=True)
    stages = []
    monkeypatch.setattr(ProgressDisplay, "stage", lambda self, index, name: stages.append((index, name)))
    dask = run_sweep(study, tmp_path / "dask", cache=Cache(tmp_path / "c2"), executor="dask", jobs=2, quiet=True)
    assert len(dask.computed) == 2 and list(dask.rows["status"]) == ["ok", "invalid"]
    assert sorted(stages) == [(0, "fea"), (0, "fea"), (0, "geometry"), (0, "mesh"), (0, "mesh"), (0, "mesh"),
                              (0, "path"), (1, "geometry")]  # worker stages arrived (k's error estimate meshes and
    # solves a coarser mesh, the path meshes its own one-layer mesh)
    cols = ["candidate", "status", "reason", "volume_mm3", "row_key"]
    assert dask.rows[cols].equals(serial.rows[cols])
    # the same mesh and solve in another process: k and the stresses agree to round-off
    for col in ("k_Nm_per_rad", "stall_von_mises_max_MPa", "impact_reaction_per_bolt_N"):
        assert dask.rows.loc[0, col] == pytest.approx(serial.rows.loc[0, col], rel=1e-9), col
