"""The thesis's trend on the default study (thesis fig. 5.3): the stall displacement falls with
beam thickness and with beam count. Every valid candidate of the default design space is solved
(the linear load cases the sweep's table reports) on the sweep's error-estimate mesh (1.5x coarser
than the default, same sizing rules)."""

from __future__ import annotations

import pandas as pd
import pytest

from seadesign.design.study import load_study
from seadesign.run.cache import Cache
from seadesign.sweep.stages import COARSENING, SolverSettings, tetrahedralize, unit_response


@pytest.mark.slow
def test_displacement_falls_with_thickness_and_beam_count(tmp_path):
    study = load_study("wolfgang_knee")
    cache, rows = Cache(tmp_path / "cache"), []
    for candidate in study.candidates():
        checked, part = study.check(candidate)
        if not checked.valid:
            continue
        mesh = tetrahedralize(study, checked, part, cache, coarsening=COARSENING)
        unit = unit_response(mesh, study, checked, SolverSettings()).results
        stall = unit.at(study.load_cases.stall_torque_Nm, study.load_cases.impact_torque_Nm).stall
        axes = dict(checked.values)
        rows.append((axes["beam_count"], axes["beam_thickness_mm"], stall.bearing_displacement_mm))
    assert len(rows) >= 15
    d = pd.DataFrame(rows, columns=["beams", "thickness_mm", "displacement_mm"]).pivot_table(
        index="beams", columns="thickness_mm", values="displacement_mm")
    for thickness in d.columns:  # more beams: smaller displacement
        series = d[thickness].dropna()
        assert series.is_monotonic_decreasing and series.is_unique, (thickness, series.to_dict())
    for count, row in d.iterrows():  # thicker beams: smaller displacement
        series = row.dropna()
        assert series.is_monotonic_decreasing and series.is_unique, (count, series.to_dict())
