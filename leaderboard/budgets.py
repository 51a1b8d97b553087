"""A run's training budget as its result file records it: env steps, and how it was evaluated.

Runs of different budgets are different experiments (a run id hashes its budget): the leaderboard
keeps their rows apart (:mod:`leaderboard.sources`) and compares a row with DQN runs of its own
budget only (:func:`leaderboard.improvement.improvements_over_dqn`).
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

from empathy_zoo.experiment.records import RunResult

__all__ = ["RunBudget", "budget_of", "budgets_of", "shows_evaluation"]


@dataclass(frozen=True)
class RunBudget:
    """How long a run trained and how it was evaluated."""

    steps: int
    """Training env steps (the result file's ``steps``)."""
    eval_interval: int | None
    """Env steps between greedy evaluations (``config.eval_interval``); ``None`` where the file has none."""
    eval_episodes: int | None
    """Episodes per greedy evaluation (``config.eval_episodes``); ``None`` where the file has none."""

    def text(self, with_evaluation: bool = True) -> str:
        """``"30,000 steps"``, with ``", eval 10,000 × 10"`` (a greedy evaluation of 10 episodes
        every 10,000 steps; ``?`` for what the file does not record) if ``with_evaluation``."""
        steps = f"{self.steps:,} steps"
        if not with_evaluation:
            return steps
        interval = "?" if self.eval_interval is None else f"{self.eval_interval:,}"
        episodes = "?" if self.eval_episodes is None else f"{self.eval_episodes:,}"
        return f"{steps}, eval {interval} × {episodes}"

    def order(self) -> tuple[int, int, int]:
        """Sort key: steps, then evaluation interval and episodes (an unrecorded one first)."""
        return self.steps, self.eval_interval or 0, self.eval_episodes or 0


def budget_of(run: RunResult) -> RunBudget:
    """The budget of ``run``."""
    return RunBudget(run.steps, run.config.eval_interval, run.config.eval_episodes)


def budgets_of(runs: Iterable[RunResult]) -> tuple[RunBudget, ...]:
    """The distinct budgets of ``runs``, ascending."""
    return tuple(sorted({budget_of(run) for run in runs}, key=RunBudget.order))


def shows_evaluation(budgets: Iterable[RunBudget]) -> bool:
    """Whether a budget's text must name its evaluation to tell ``budgets`` apart: their
    evaluation interval or episodes differ."""
    return len({(budget.eval_interval, budget.eval_episodes) for budget in budgets}) > 1
