"""When a run starts learning and when it stops exploring, as its settings declare them.

A settings class may have a method ``training_phases()`` that returns a :class:`TrainingPhases`
(or ``None`` where its settings have no warm-up and no ε schedule): Empathic DQN's and the SB3
methods' do. Before anything trains, the suite reads it to refuse a budget that ends inside the
warm-up and to warn of an ε schedule that does not reach its floor within the budget
(:mod:`empathy_zoo.experiment.budget_fit`). A settings class without the method declares nothing
and is not checked.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

__all__ = ["TrainingPhases", "training_phases"]


@dataclass(frozen=True)
class TrainingPhases:
    """A run's warm-up and the end of its ε decay, in env steps, with the settings that set them."""

    learning_starts: int
    """Env steps taken before the first gradient step (the warm-up): a budget of no more steps learns nothing."""
    learning_starts_setting: str
    """The setting that sets :attr:`learning_starts`, as a sweep file's ``[settings]`` names it
    (``learning_starts``; ``algorithm_kwargs.learning_starts`` for an SB3 method)."""
    learning_starts_option: str = ""
    """The ``train`` option that sets it, ``{}`` standing for the value (``--learning-starts {}``;
    ``--algorithm-kwargs learning_starts={}`` for an SB3 method); ``""``: none is named."""
    learning_starts_least: int = 0
    """The smallest value the settings class accepts for it (Empathic DQN: its ``batch_size``)."""
    exploration_ends: int | None = None
    """The env step at which ε reaches its floor (``None``: no ε schedule)."""
    exploration_rule: str = ""
    """How :attr:`exploration_ends` follows from the settings, as a phrase
    (``"learning_starts + epsilon_decay_steps"``)."""
    exploration_fix: Callable[[int], str] | None = field(default=None, compare=False)
    """For a budget of that many env steps, what to set for ε to reach its floor within it, as a
    phrase (``"epsilon_decay_steps = 28,000"``); ``None``: no suggestion."""


def training_phases(settings: object) -> TrainingPhases | None:
    """What ``settings`` declare through their ``training_phases()`` (``None`` where they have no
    such method, or it declares nothing)."""
    declare = getattr(settings, "training_phases", None)
    if not callable(declare):
        return None
    phases = declare()
    if phases is not None and not isinstance(phases, TrainingPhases):
        raise ValueError(f"{type(settings).__name__}.training_phases() must return a TrainingPhases or None, got {phases!r}")
    return phases
