"""The trainers' shared stop rule, on sequences worked by hand."""

from __future__ import annotations

from seadesign.corrector.early_stopping import KeepBest


def _run(values, admissible=None, **rule):
    stop, kept = KeepBest(**rule), []
    for epoch, value in enumerate(values):
        if stop.update(epoch, value, True if admissible is None else admissible[epoch]):
            kept.append(epoch)
        if stop.exhausted:
            return stop, kept, epoch
    return stop, kept, None


def test_a_new_best_below_the_improvement_threshold_is_kept_but_counts_as_stale():
    # 5 -> 4 improves by 20 %; 4.5 does not; 3.99 is a new best but only 0.25 % better: stale 2 = patience
    stop, kept, ended = _run([5.0, 4.0, 4.5, 3.99, 1.0], patience=2, min_improvement=0.01)
    assert kept == [0, 1, 3] and stop.best_epoch == 3 and stop.best == 3.99 and ended == 3


def test_without_a_threshold_any_lower_value_resets_the_patience():
    stop, kept, ended = _run([5.0, 4.0, 4.5, 3.99, 4.2, 4.1], patience=2)
    assert kept == [0, 1, 3] and ended == 5 and stop.best_epoch == 3


def test_an_inadmissible_epoch_is_never_the_best_and_is_stale():
    stop, kept, ended = _run([5.0, 1.0, 6.0, 6.0, 3.0], admissible=[True, False, True, True, True], patience=3)
    assert kept == [0] and stop.best == 5.0 and ended == 3
