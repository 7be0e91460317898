"""A reduced exploration of the real knee study (`wolfgang_knee_explore`: seven axes, the material among them,
on the full pipeline with a coarse mesh and a small budget) through the design of experiments and at least two
search rounds. No answer rests on missing data: with no sourced cyclic strain limit for either material, no design
can be feasible; a design that meets every judged requirement is conditional and names the datum it needs."""

from __future__ import annotations

import dataclasses

import pytest

from seadesign.design.study import load_study
from seadesign.explore.explorer import ExplorerSettings
from seadesign.explore.study_run import explore_study
from seadesign.run.cache import Cache


@pytest.mark.slow  # eight coarse full-path evaluations and two rounds of fitting and search
def test_a_reduced_knee_exploration_runs_search_rounds_and_never_calls_a_conditional_design_feasible(tmp_path):
    study = load_study("wolfgang_knee_explore")
    coarse = dataclasses.replace(study.mesh, elements_across_beam=1.0, elements_per_circle=7.0, layers=1.0)
    study = dataclasses.replace(study, mesh=coarse)
    # most of this space cannot be built (the knee run screened 89 of 115 invalid): room for 20 screenings per
    # evaluation, so that the small budget reaches the search rounds
    loop = ExplorerSettings(budget=8, batch=2, seed=0, screen_factor=20)
    run = explore_study(study, tmp_path / "out", loop, cache=Cache(tmp_path / "c"), jobs=2, quiet=True)
    t = run.exploration.evaluated
    searched = [r for r in run.exploration.rounds if r.index > 0]
    assert len(searched) >= 2, run.exploration.stop_reason  # rounds after the design of experiments
    assert len(t) <= 8 and t["status"].isin(["ok", "failed"]).all()
    assert not t["feasible"].any()  # neither material sources a cyclic strain limit
    assert (t["conditional"] == (t["meets_judged"] & t["solved"])).all()
    for text in t.loc[t["conditional"], "not_judged"]:
        assert "stall strain: passes if" in text and "cyclic strain limit is at least" in text
    d = run.decision
    assert d.index is not None and not d.feasible
    if t.loc[d.index, "conditional"]:
        assert any("cyclic strain limit" in n for n in d.not_judged)
