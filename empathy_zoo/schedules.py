"""The ε schedule of SPEC §6, as a pure function: the learner explores by it, and the leaderboard
reads it back from a result file's settings (to compare a run with the exact reference at the ε
it trained with) without importing any learner."""

from __future__ import annotations

from typing import Protocol

__all__ = ["EpsilonSchedule", "linear_epsilon"]


class EpsilonSchedule(Protocol):
    """The settings the schedule reads (``EmpathicDQNSettings`` has them, as does any object
    built from a result file's ``config.settings``)."""

    @property
    def learning_starts(self) -> int: ...
    @property
    def epsilon_start(self) -> float: ...
    @property
    def epsilon_end(self) -> float: ...
    @property
    def epsilon_decay_steps(self) -> int: ...


def linear_epsilon(settings: EpsilonSchedule, env_step: int) -> float:
    """ε after ``env_step`` steps of a run: 1 during warm-up, then linear to ``epsilon_end``."""
    if env_step < settings.learning_starts:
        return 1.0
    fraction = min(1.0, (env_step - settings.learning_starts) / settings.epsilon_decay_steps)
    return settings.epsilon_start + fraction * (settings.epsilon_end - settings.epsilon_start)
