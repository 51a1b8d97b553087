"""Plug-in methods with settings of their own, for the command line's tests (named as
``helpers_cli_method:NAME``: pytest puts tests/ on the path), and tiny ``train`` options."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from agents.base import Method
from agents.empathic_dqn import EmpathicDQN
from agents.settings import EmpathicDQNSettings

TINY = [
    "--steps",
    "300",
    "--eval-interval",
    "150",
    "--eval-episodes",
    "2",
    "--max-cycles",
    "50",
    "--learning-starts",
    "32",
    "--batch-size",
    "32",
    "--replay-capacity",
    "300",
    "--hidden-size",
    "16",
    "--target-update-interval",
    "50",
    "--epsilon-decay-steps",
    "200",
    "--no-progress",
]
"""``train`` options of a run that takes a second or two."""


@dataclass(frozen=True)
class AverseSettings(EmpathicDQNSettings):
    """Empathic DQN's settings and three of this method's own."""

    aversion: float = 1.0
    """How strongly the robot shies away from harm (this method's own setting)."""
    cautious: bool = False
    """Whether the robot moves with care (a switch of this method's own)."""
    widths: tuple[int, ...] = (16, 16)
    """Layer widths of an imagined network."""


AVERSE_DQN = Method(
    name="averse_dqn",
    learner=EmpathicDQN,
    settings=AverseSettings,
    preset={"selfishness": 1.0},
    label=lambda s: f"Averse DQN ({s.aversion:g})",
    description="DQN with an aversion setting",
)
"""A method whose settings have fields no registered method has; it fixes ``selfishness``."""


@dataclass(frozen=True)
class OddSettings:
    """Settings some of whose fields cannot be options."""

    seed: int = 0
    """A field named like a run option (``--seed`` is the run's)."""
    extras: Mapping[str, Any] = field(default_factory=dict)
    """A table, read as KEY=VALUE pairs."""
    rate: float | None = None
    """A number or nothing."""


ODD = Method(name="odd", learner=EmpathicDQN, settings=OddSettings)
"""A method that is only parsed, never trained."""
