"""The learner plug-in interface the runner drives.

A learner trains ``K`` independent runs of one method on one environment in lockstep (``K = 1``
is an ordinary single run). Every array has a leading run axis ``K`` and an env axis ``M``
(environments per run). The runner never looks inside a learner: it asks for actions, hands
over what happened, and saves/loads ``state_dict()`` for checkpoints.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any, Protocol

import numpy as np

from agents.rewards import RewardTransform
from agents.step_batch import StepBatch

__all__ = ["StepBatch", "Learner", "Method"]


class Learner(Protocol):
    """What the runner needs of a learning method (see :mod:`agents.empathic_dqn` for one)."""

    def __init__(self, settings: Sequence[Any], seeds: Sequence[int], obs_size: int, num_actions: int, device: str) -> None: ...

    def act(self, observations: np.ndarray, greedy: bool = False) -> np.ndarray:
        """``(K, M)`` actions for ``(K, M, V)`` observations (exploring unless ``greedy``)."""

    def observe(self, batch: StepBatch) -> None:
        """Learn from one step (store it, maybe take gradient steps)."""

    def live_stats(self) -> dict[str, float]:
        """A few numbers for the progress bar (e.g. ``{"eps": 0.3}``)."""

    def state_dict(self) -> dict[str, Any]:
        """Everything needed to continue exactly: tensors, numbers, lists (``torch.save``-able,
        loadable with ``weights_only=True``). Written to the checkpoint file at once, so tensors
        may be the live ones (no copy of a large replay memory is needed)."""

    def load_state_dict(self, state: dict[str, Any]) -> None: ...

    def memory_bytes_per_run(self) -> int:
        """Bytes each run holds (replay and networks)."""


@dataclass(frozen=True)
class Method:
    """A registered learning method: a learner class plus the settings it fixes."""

    name: str
    """Registry name (``--method``)."""
    learner: type
    """The :class:`Learner` class."""
    settings: type
    """Its settings dataclass."""
    preset: dict[str, Any] = field(default_factory=dict)
    """Settings this method fixes (a user may not override them)."""
    reward: RewardTransform | None = None
    """What its runs train on instead of the environment's reward (``None``: that reward)."""
    in_view_only: bool = False
    """Swap with the other agent only while it stands in the learner's window: elsewhere
    ``StepBatch.other_present`` is False (no other-term) and ``swapped_next_obs`` is zeros. The
    paper's swap is omniscient (seeing through walls is its future work)."""
    label: Callable[[Any], str] | None = None
    """Display name of a run from its settings (defaults to the name)."""
    description: str = ""
    """One line for ``empathy-zoo methods``."""

    def make_settings(self, overrides: dict[str, Any]) -> Any:
        """The method's settings with ``overrides``; overriding a preset raises ``ValueError``."""
        clash = sorted(k for k in overrides if k in self.preset and overrides[k] != self.preset[k])
        if clash:
            raise ValueError(f"method {self.name!r} fixes {', '.join(f'{k}={self.preset[k]!r}' for k in clash)}")
        known = set(self.settings.__dataclass_fields__)
        unknown = sorted(set(overrides) - known)
        if unknown:
            raise ValueError(f"unknown setting(s) {unknown} for method {self.name!r}; known: {sorted(known)}")
        for name, value in overrides.items():  # (a settings class need not think of inf and NaN)
            if isinstance(value, float) and not math.isfinite(value):
                raise ValueError(f"{name} must be a finite number, got {value!r}")
        return self.settings(**{**overrides, **self.preset})

    def display_name(self, settings: Any) -> str:
        return self.label(settings) if self.label else self.name
