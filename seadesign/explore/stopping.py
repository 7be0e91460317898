"""When the explorer stops: small rules read after each round, composed in order; the first that fires names
the stop (`Explorer.stop_reason`)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol


@dataclass(frozen=True)
class Progress:
    """What the rules read after a round."""

    evaluations: int  # full evaluations so far
    screenings: int  # cheap screenings so far
    rounds_without_move: int  # rounds in a row whose verified designs did not move the front
    empty_round: bool  # the last round's proposals and spares all screened invalid (or none could be screened)


class StopRule(Protocol):
    def reason(self, progress: Progress) -> str | None:
        """Why to stop now, or None to go on."""


@dataclass(frozen=True)
class EvaluationBudget:
    """The budget of full evaluations is spent."""

    evaluations: int

    def reason(self, progress: Progress) -> str | None:
        return "budget spent" if progress.evaluations >= self.evaluations else None


@dataclass(frozen=True)
class StalledFront:
    """`patience` rounds in a row have not moved the front."""

    patience: int

    def reason(self, progress: Progress) -> str | None:
        return f"the front did not move in {self.patience} rounds" if progress.rounds_without_move >= self.patience \
            else None


@dataclass(frozen=True)
class ScreeningBudget:
    """A round found no valid design and the screenings are spent (a round that finds valid designs goes on)."""

    screenings: int

    def reason(self, progress: Progress) -> str | None:
        return "the screening budget is spent" if progress.empty_round and progress.screenings >= self.screenings \
            else None


def first_reason(rules: tuple[StopRule, ...], progress: Progress) -> str | None:
    """The reason of the first rule that fires, None when none does."""
    return next((r for r in (rule.reason(progress) for rule in rules) if r is not None), None)
