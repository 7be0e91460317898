"""The explorer's parts against independent references: the axes' unit cube, the design of experiments,
the surrogates' leave-one-out error against refitting without each point, the feasibility classifier on a
known boundary, Sobol indices of a function whose indices are known in closed form, and the stop rules and
ask/tell of the explorer."""

from __future__ import annotations

import numpy as np
import pytest
from sklearn.gaussian_process import GaussianProcessRegressor

from seadesign.design.space import Axis
from seadesign.explore.doe import initial_design
from seadesign.explore.encoding import Encoding
from seadesign.explore.explorer import Explorer, ExplorerSettings
from seadesign.explore.models import Models
from seadesign.explore.sensitivity import sobol_indices
from seadesign.explore.stopping import EvaluationBudget, Progress, StalledFront, first_reason
from seadesign.explore.surrogate import FeasibilityClassifier, Surrogate

AXES = (Axis("thickness_mm", bounds=(6.0, 20.0)), Axis("beam_count", (3, 4, 6, 10)),
        Axis("material", ("ninjaflex", "cheetah")))


def test_unit_cube_round_trip_and_snapping():
    enc = Encoding(AXES)
    point = (("thickness_mm", 13.0), ("beam_count", 6), ("material", "cheetah"))
    x = enc.encode(point)
    assert x == pytest.approx([0.5, 3 / 7, 1.0])
    assert enc.decode(x) == point
    assert enc.decode([0.5, 0.5, 0.2]) == (("thickness_mm", 13.0), ("beam_count", 6), ("material", "ninjaflex"))
    assert enc.snap([[0.25, 0.9, 0.7]]) == pytest.approx(np.array([[0.25, 1.0, 1.0]]))
    assert enc.grid_size() is None
    discrete = Encoding(AXES[1:])
    assert discrete.grid_size() == 8 and len({tuple(r) for r in discrete.grid()}) == 8


def test_initial_design_is_the_full_factorial_or_a_space_filling_sample():
    discrete = Encoding(AXES[1:])
    assert len(initial_design(discrete, 8, seed=0)) == 8  # every design
    X = initial_design(Encoding(AXES), 12, seed=0)
    assert len(X) <= 12 and np.all((0 <= X) & (X <= 1))
    # a Latin hypercube: each of the 12 strata of the continuous axis holds one point
    assert sorted(np.floor(X[:, 0] * 12).astype(int)) == list(range(12))
    assert np.array_equal(X, initial_design(Encoding(AXES), 12, seed=0))  # seeded


def test_leave_one_out_equals_refitting_without_each_point():
    rng = np.random.default_rng(3)
    X = rng.random((14, 2))
    y = np.exp(1.5 * X[:, 0] - X[:, 1]) * (1 + 0.3 * np.sin(5 * X[:, 1]))
    s = Surrogate(log=True, seed=0).fit(X, y)
    kernel = s.gp.kernel_  # the fitted hyperparameters, held fixed (as the closed form assumes)
    refit = []
    for i in range(len(y)):
        keep = np.arange(len(y)) != i
        gp = GaussianProcessRegressor(kernel, optimizer=None, normalize_y=True).fit(X[keep], np.log(y[keep]))
        refit.append(np.exp(gp.predict(X[i:i + 1])[0]))
    # normalize_y re-standardises each subset, which the closed form does not: measured 1.6e-5 apart at most
    assert s.loo() == pytest.approx(np.array(refit), rel=1e-4)
    err = s.loo_error()
    assert err.n == 14 and err.mean_abs_rel == pytest.approx(np.mean(np.abs(np.array(refit) - y) / y), rel=1e-3)


def test_classifier_learns_a_disc():
    rng = np.random.default_rng(0)
    X = rng.random((80, 2))
    inside = np.linalg.norm(X - 0.5, axis=1) < 0.3
    clf = FeasibilityClassifier(seed=0).fit(X, inside)
    probe = rng.random((400, 2))
    truth = np.linalg.norm(probe - 0.5, axis=1) < 0.3
    assert np.mean((clf.predict_proba(probe) >= 0.5) == truth) > 0.9


def test_sobol_indices_of_an_additive_function():
    """f = x1 + 2 x2 (x uniform): S_1 = 1 / 5, S_2 = 4 / 5, no interaction (S = ST)."""
    enc = Encoding((Axis("a", bounds=(0.0, 1.0)), Axis("b", bounds=(0.0, 1.0))))
    X = initial_design(enc, 20, seed=1)
    s = Surrogate(seed=0).fit(X, X[:, 0] + 2 * X[:, 1])
    models = Models({"f": s}, FeasibilityClassifier(), ("f",), ())
    idx = sobol_indices(enc, models, ["f"], seed=0).set_index("axis")
    assert idx.loc["a", "S1"] == pytest.approx(0.2, abs=0.05) and idx.loc["b", "S1"] == pytest.approx(0.8, abs=0.05)
    assert idx.loc["a", "ST"] == pytest.approx(0.2, abs=0.05) and idx.loc["b", "ST"] == pytest.approx(0.8, abs=0.05)


def test_the_stop_rules_compose_and_the_first_that_fires_names_the_stop():
    rules = ExplorerSettings(budget=10, patience=2, screen_factor=3).stop_rules()
    assert first_reason(rules, Progress(9, 29, 1, False)) is None
    assert first_reason(rules, Progress(10, 0, 0, False)) == "budget spent"
    assert first_reason(rules, Progress(10, 0, 2, False)) == "the front did not move in 2 rounds"
    assert first_reason(rules, Progress(5, 30, 0, False)) is None  # screenings spent, but the round found designs
    assert first_reason(rules, Progress(5, 30, 0, True)) == "the screening budget is spent"
    assert first_reason((), Progress(10, 30, 5, True)) is None


def test_ask_and_tell_stop_on_the_callers_rule():
    """The caller drives the explorer and replaces its stop rules: it stops after the round that reaches 7
    evaluations, though the settings' budget allows 20, and asks nothing more."""
    from helpers_analytic import BNH

    problem = BNH()
    explorer = Explorer(problem, ExplorerSettings(budget=20, batch=2, seed=0, patience=100), rules=(EvaluationBudget(7),))
    told = []
    while (X := explorer.ask()) is not None:
        explorer.tell(X, problem.evaluate(X))
        told.append(len(X))
    assert explorer.stop_reason == "budget spent" and explorer.ask() is None
    assert sum(told[:-1]) < 7 <= sum(told) == problem.evaluations == len(explorer.result().evaluated) < 20
    assert all(n <= 2 for n in told[1:])  # after the initial design, one batch a round

    capped = BNH()
    explorer = Explorer(capped, ExplorerSettings(budget=8, batch=2, seed=0), rules=(StalledFront(100),))
    while (X := explorer.ask()) is not None:  # rules without a budget: the settings' budget still caps the run
        explorer.tell(X, capped.evaluate(X))
    assert explorer.stop_reason == "budget spent" and capped.evaluations == 8
