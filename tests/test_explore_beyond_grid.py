"""NinjaFlex only, beam count x beam thickness as the grid's axes, and the axial thickness opened as a
continuous axis: the explorer finds a design off the grid that beats every grid point on the study's own
criterion (feasible where no grid point is; with none feasible, a smaller total violation). Coarse mesh."""

from __future__ import annotations

import re

import pytest

from seadesign.design.study import load_study
from seadesign.explore.explorer import ExplorerSettings, explore
from seadesign.explore.spring_problem import SpringProblem
from seadesign.run.cache import Cache
from seadesign.sweep.rank import rank
from seadesign.sweep.runner import run_sweep
from sweep_helpers import write_tiny_study

GRID_THICKNESS_MM = 9.0  # the default study's fixed axial thickness


@pytest.mark.slow  # 12 full-path evaluations on a coarse mesh: 4-8 min on two busy cores
def test_a_continuous_thickness_beats_every_grid_point(tmp_path):
    grid_path = write_tiny_study(tmp_path, name="grid", beam_count="[4, 6]", beam_thickness_mm="[6.0, 8.0]")
    text = re.sub(r"(?m)^thickness_mm = 9.0.*$", "", grid_path.read_text())
    open_path = tmp_path / "open.toml"
    open_path.write_text(text.replace('name = "grid"', 'name = "open"').replace(
        "[design_space]\n", "[design_space]\nthickness_mm = {min = 6.0, max = 20.0}\n"))
    grid, opened = load_study(grid_path), load_study(open_path)
    assert opened.material.key == "ninjaflex" and grid.fixed["thickness_mm"] == GRID_THICKNESS_MM
    cache = Cache(tmp_path / "cache")
    ranked, _ = rank(run_sweep(grid, tmp_path / "grid", cache=cache, jobs=2, quiet=True).rows, grid)
    assert (ranked["status"] == "ok").all()
    result = explore(SpringProblem(opened, tmp_path / "open", cache=cache, jobs=2), ExplorerSettings(budget=8, batch=2))
    t = result.evaluated
    best = t.loc[result.best]
    assert best["thickness_mm"] != GRID_THICKNESS_MM  # off the grid
    if ranked["feasible"].any():
        assert best["feasible"]
    else:
        assert best["feasible"] or best["total_violation"] < ranked["total_violation"].min()
