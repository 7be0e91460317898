"""Early stopping that keeps the best epoch, shared by the corrector's trainers.

An epoch's validation value (lower is better) counts only when the trainer calls it admissible (the closed
loop's: its validation commands rest without chatter). The best admissible epoch is kept; the run stops after
`patience` epochs in a row that did not improve on the best by more than `min_improvement` (relative).
"""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass
class KeepBest:
    """The stop rule's state: the best admissible value, its epoch, the epochs since an improvement."""

    patience: int
    min_improvement: float = 0.0
    best: float = math.inf
    best_epoch: int = 0
    stale: int = 0

    def update(self, epoch: int, value: float, admissible: bool = True) -> bool:
        """Record an epoch's value; whether it is the new best (the trainer keeps that epoch's state)."""
        improved = admissible and value < self.best * (1.0 - self.min_improvement)
        self.stale = 0 if improved else self.stale + 1
        if admissible and value < self.best:
            self.best, self.best_epoch = value, epoch
            return True
        return False

    @property
    def improved(self) -> bool:
        """Whether the last epoch improved on the best by more than `min_improvement`."""
        return self.stale == 0

    @property
    def exhausted(self) -> bool:
        """Whether `patience` epochs in a row did not improve: stop."""
        return self.stale >= self.patience
