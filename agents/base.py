"""The learner plug-in interface the runner drives.

A learner trains ``K`` independent runs of one method on one environment in lockstep (``K = 1``
is an ordinary single run). Every array has a leading run axis ``K`` and an env axis ``M``
(environments per run). The runner never looks inside a learner: it asks for actions, hands
over what happened, and saves/loads ``state_dict()`` for checkpoints.
"""

from __future__ import annotations

import inspect
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, fields
from typing import Any, Protocol

import numpy as np

from agents.rewards import RewardTransform, configure_transform, transform_config, transform_fields
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
    """What its runs train on instead of the environment's reward (``None``: that reward), with
    its default fields; a run may set other values of them (:meth:`make_reward`: sweep keys and
    ``train`` options, like the settings)."""
    in_view_only: bool = False
    """Swap with the other agent only while it stands in the learner's window: elsewhere
    ``StepBatch.other_present`` is False, ``other_unseen`` is True (the other is unseen, not
    harmed: Empathic DQN's target is then the robot's own, SPEC §4) and ``swapped_next_obs`` is
    zeros. The paper's swap is omniscient (seeing through walls is its future work)."""
    label: Callable[..., str] | None = None
    """Display name of a run from its settings (defaults to the name). A label that takes two
    arguments is also given the run's reward transform and shows its fields itself; to any other,
    the fields a run sets to other values than the method's are appended, as
    ``"DQN + inequity aversion (disadvantageous=0.3)"`` (a field named like a setting as
    ``reward.<field>=…``; :meth:`display_name`)."""
    description: str = ""
    """One line for ``empathy-zoo methods``."""

    def make_settings(self, overrides: dict[str, Any]) -> Any:
        """The method's settings with ``overrides``; overriding a preset raises ``ValueError``."""
        clash = sorted(k for k in overrides if k in self.preset and overrides[k] != self.preset[k])
        if clash:
            raise ValueError(f"method {self.name!r} fixes {', '.join(f'{k}={self.preset[k]!r}' for k in clash)}")
        known = {f.name for f in fields(self.settings)}
        unknown = sorted(set(overrides) - known)
        if unknown:
            raise ValueError(f"unknown setting(s) {unknown} for method {self.name!r}; known: {sorted(known)}")
        for name, value in overrides.items():  # (a settings class need not think of inf and NaN)
            if isinstance(value, float) and not math.isfinite(value):
                raise ValueError(f"{name} must be a finite number, got {value!r}")
        return self.settings(**{**overrides, **self.preset})

    def make_reward(self, overrides: Mapping[str, Any]) -> RewardTransform | None:
        """The method's reward transform with the fields ``overrides`` set (the transform itself
        when there are none); an unknown field or a value of the wrong type raises ``ValueError``
        naming the fields it has."""
        return configure_transform(self.reward, overrides, self.name)

    def reward_fields(self) -> dict[str, Any]:
        """``{field: type}`` of the fields of its reward transform (``{}`` without one)."""
        return transform_fields(self.reward)

    def display_name(self, settings: Any, reward: RewardTransform | None = None, shown: Sequence[str] = ()) -> str:
        """A run's name in tables from its settings and its reward transform (``None``: the
        method's own); see :attr:`label`. The transform's fields named in ``shown`` are shown even
        at their defaults (a sweep's grid shows its every value, the default's too)."""
        reward = self.reward if reward is None else reward
        if self.label is None:
            base = self.name
        elif _takes_two(self.label):
            return self.label(settings, reward)
        else:
            base = self.label(settings)
        changed = _changed_fields(self.reward, reward, shown)
        settings_fields = getattr(self.settings, "__dataclass_fields__", {})
        parts = [f"{'reward.' if name in settings_fields else ''}{name}={_shown(value)}" for name, value in changed.items()]
        return f"{base} ({', '.join(parts)})" if parts else base


def _takes_two(label: Callable[..., str]) -> bool:
    """``label`` takes a second positional argument (the reward transform)."""
    try:
        parameters = list(inspect.signature(label).parameters.values())
    except (TypeError, ValueError):
        return False
    positional = [p for p in parameters if p.kind in (p.POSITIONAL_ONLY, p.POSITIONAL_OR_KEYWORD)]
    return len(positional) >= 2 or any(p.kind is p.VAR_POSITIONAL for p in parameters)


def _changed_fields(default: RewardTransform | None, reward: RewardTransform | None, shown: Sequence[str] = ()) -> dict[str, Any]:
    """The fields of ``reward`` whose values differ from ``default``'s, and those in ``shown``, in
    declaration order."""
    if default is None or reward is None or type(default) is not type(reward):
        return {}
    before, after = transform_config(default) or {}, transform_config(reward) or {}
    return {
        name: value
        for name, value in after.items()
        if name != "name" and (name in shown or repr(before.get(name)) != repr(value))
    }


def _shown(value: Any) -> str:
    """A field's value in a label: a number as ``:g`` prints it (``0.3``, ``1``, ``-100``)."""
    return f"{value:g}" if isinstance(value, float) else str(value)
