"""The thesis's trend on the default study (thesis fig. 5.3): the stall displacement falls with
beam thickness and with beam count. Every valid candidate of the default design space is solved
on the sweep's error-estimate mesh (1.5x coarser than the default, same sizing rules)."""

from __future__ import annotations

import dataclasses

import pytest

from seadesign.run.cache import Cache
from seadesign.sweep.stages import COARSENING
from seadesign.design.study import load_study
from seadesign.sweep.runner import run_sweep


@pytest.mark.slow
def test_displacement_falls_with_thickness_and_beam_count(tmp_path):
    study = load_study("wolfgang_knee")
    coarse = study.mesh.scaled(1.0 / COARSENING)
    run = run_sweep(dataclasses.replace(study, mesh=coarse), tmp_path, cache=Cache(tmp_path / "cache"), quiet=True)
    ok = run.rows[run.rows["status"] == "ok"]
    assert len(ok) >= 15 and set(run.rows["status"]) <= {"ok", "invalid"}
    d = ok.pivot_table(index="beam_count", columns="beam_thickness_mm", values="stall_bearing_displacement_mm")
    for thickness in d.columns:  # more beams: smaller displacement
        series = d[thickness].dropna()
        assert series.is_monotonic_decreasing and series.is_unique, (thickness, series.to_dict())
    for count, row in d.iterrows():  # thicker beams: smaller displacement
        series = row.dropna()
        assert series.is_monotonic_decreasing and series.is_unique, (count, series.to_dict())
