"""The closed-loop goal's bookkeeping on hand-made runs, against gains worked out by hand: the cell table, the
verdict over the cases (both ways: met and robust, and not) and the winner."""

from __future__ import annotations

import numpy as np
import pytest

from seadesign.corrector.closedloop import ClosedLoopRun
from seadesign.corrector.goal import HELD_OUT_CASE, goal_table, verdict, winner
from seadesign.twin import Trial

TRIALS = [Trial("front", 0.1, 1.0), Trial("back", 0.2, 1.0)]
#: |Hall error| (rad) per trial of the baselines: the best is pi's 0.08 in trial 0 and none's 0.2 in trial 1
BASELINES = {"none": (0.1, 0.2), "pi": (0.08, 0.3), "feedforward": (0.12, 0.25)}


def _run(name: str, errors: tuple[float, float], flagged: bool = False) -> ClosedLoopRun:
    """A run whose |Hall error| is constant per trial (so mean = peak), both knees alike."""
    target = np.zeros((2, 10, 2))
    hall = np.broadcast_to(np.array(errors)[:, None, None], target.shape).copy()
    return ClosedLoopRun(name, 100.0, TRIALS, target, hall, hall, target, False, flagged)


def _goal(candidates: dict[str, tuple[float, float]], flagged: tuple[str, ...] = ()) -> dict:
    runs = [_run(n, e) for n, e in BASELINES.items()] + [_run(n, e, n in flagged) for n, e in candidates.items()]
    return {name: goal_table({"hanging": runs}, name) for name in candidates}


def test_goal_table_gains_against_the_best_baseline_per_cell():
    table = _goal({"a": (0.04, 0.1), "b": (0.06, 0.19)})
    a, b = table["a"], table["b"]
    np.testing.assert_allclose(a.gain, [0.5, 0.5])
    assert list(a.best_baseline) == ["pi", "none"] and a.meets_goal.all()
    np.testing.assert_allclose(b.gain, [0.25, 0.05])
    assert not b.meets_goal.any()  # under 30 % below the best baseline in both cells


def test_verdict_and_winner_over_the_cases_both_ways():
    """a: meets the goal nominally and on the held-out gait, keeps >= half its gain in the robustness cases (shares
    0.5 and 0.6); b: better nominal, but flagged in one robustness case; c: not flagged but keeps only 0.4 of its
    nominal gain in one cell; d: misses the goal on the held-out gait; e: meets and is robust, with larger errors."""
    cases = {
        "nominal": _goal({"a": (0.04, 0.1), "b": (0.02, 0.05), "c": (0.04, 0.1), "d": (0.04, 0.1), "e": (0.05, 0.12)}),
        HELD_OUT_CASE: _goal({"a": (0.04, 0.1), "b": (0.02, 0.05), "c": (0.04, 0.1), "d": (0.06, 0.1),
                              "e": (0.05, 0.12)}),
        "k x0.7": _goal({"a": (0.06, 0.14), "b": (0.02, 0.05), "c": (0.064, 0.1), "d": (0.04, 0.1), "e": (0.06, 0.15)},
                        flagged=("b",)),
    }
    verdicts = {n: verdict({case: goals[n] for case, goals in cases.items()}) for n in "abcde"}
    assert verdicts["a"] == pytest.approx({"meets_goal": True, "robust": True, "kept_share_min": 0.5,
                                           "mean_abs_error_rad": np.mean([0.07, 0.07, 0.1])})
    assert verdicts["b"]["meets_goal"] and not verdicts["b"]["robust"]
    assert verdicts["c"]["meets_goal"] and not verdicts["c"]["robust"] and verdicts["c"]["kept_share_min"] == pytest.approx(0.4)
    assert not verdicts["d"]["meets_goal"] and verdicts["d"]["robust"]
    assert verdicts["e"]["meets_goal"] and verdicts["e"]["robust"]
    assert winner(verdicts) == "a"  # b has the lowest error but is not robust; e qualifies with larger errors
    assert winner({n: verdicts[n] for n in "bcd"}) is None
