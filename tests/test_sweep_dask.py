"""The sweep on a Dask LocalCluster gives the same rows as the local executor."""

from __future__ import annotations

import pytest

from seadesign.run.cache import Cache
from seadesign.run.progress import ProgressDisplay
from seadesign.design.study import load_study
from seadesign.sweep.runner import run_sweep
from sweep_helpers import write_tiny_study

pytest.importorskip("distributed")


def test_dask_local_cluster_matches_serial_and_reports_stages(tmp_path, monkeypatch):
    # an invalid-only study keeps this to the geometry stage: what is tested is the executor
    study = load_study(write_tiny_study(tmp_path, beam_count="[10]", beam_thickness_mm="[6.0, 8.0]"))
    serial = run_sweep(study, tmp_path / "serial", cache=Cache(tmp_path / "c"), jobs=1, quiet=True)
    stages = []
    monkeypatch.setattr(ProgressDisplay, "stage", lambda self, index, name: stages.append((index, name)))
    dask = run_sweep(study, tmp_path / "dask", cache=Cache(tmp_path / "c2"), executor="dask", jobs=2, quiet=True)
    assert len(dask.computed) == 2
    assert sorted(stages) == [(0, "geometry"), (1, "geometry")]  # worker stages reached the display
    cols = ["candidate", "status", "reason", "volume_mm3", "row_key"]
    assert dask.rows[cols].equals(serial.rows[cols])
