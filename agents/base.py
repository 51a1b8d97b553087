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

from agents.rewards import RewardTransform, transform_config
from agents.step_batch import StepBatch
from agents.transform_fields import configure_transform, transform_fields
from empathy_zoo.method_description import check_description, default_description
from empathy_zoo.setting_values import check_recorded_settings, settings_record

__all__ = ["StepBatch", "Learner", "Method", "SETTINGS_DESCRIBE", "UPDATE_KERNELS"]

SETTINGS_DESCRIBE = ("selfishness", "gamma", "exploration")
"""The description fields a settings class may give through its ``describe()`` (:meth:`Method.describe`)."""

UPDATE_KERNELS = ("auto", "numba", "torch")
"""The gradient-step kernels a learner with a choice offers (its ``resolved_update_kernel`` and its
``update_kernel`` keyword, :class:`agents.empathic_dqn.EmpathicDQN`): compiled (``"numba"``),
PyTorch (``"torch"``), or ``"auto"``, the learner's own pick. A learner without the choice has
neither."""


class Learner(Protocol):
    """What the runner needs of a learning method (see :mod:`agents.empathic_dqn` for one).

    The methods whose docstrings begin "Optional" may be left out: the trainer calls them where
    the learner has them, and does without them elsewhere (as each one says)."""

    def __init__(
        self, settings: Sequence[Any], seeds: Sequence[int], obs_size: int, num_actions: int, device: str, *, num_others: int
    ) -> None:
        """``K`` runs: one settings object and one seed per run, the size of an observation, the
        number of actions and a torch device name, positional; and the keyword ``num_others``, how
        many other agents the environment holds (``num_cats`` / ``num_humans``: the length of the
        ``O`` axis of :class:`StepBatch`'s ``others_*`` fields). The trainer always passes it; a
        learner that cares only about the closest other agent may ignore it."""

    def act(self, observations: np.ndarray, greedy: bool = False) -> np.ndarray:
        """``(K, M)`` actions for ``(K, M, V)`` observations (exploring unless ``greedy``)."""

    def observe(self, batch: StepBatch) -> None:
        """Learn from one step (store it, maybe take gradient steps)."""

    def live_stats(self) -> dict[str, float]:
        """A few numbers for the progress bar (e.g. ``{"eps": 0.3}``)."""

    def tracked_scalars(self) -> list[dict[str, float]]:
        """Optional: per run (``K`` dicts, in run order), the figures a logged run records now, by
        the field's names (``{"losses/td_loss": …, "losses/q_values": …}``). Asked only when runs
        log (``--log``, :mod:`empathy_zoo.training.tracking`), every few hundred env steps, so it
        may compute them then; it must change nothing a run computes (no random draws, no state).
        Without it a logged run records the other :meth:`live_stats` (the ensemble's, not the run's)
        as ``learner/<name>``; ``live_stats()["eps"]`` is logged as ``charts/epsilon`` either way."""

    def state_dict(self) -> dict[str, Any]:
        """Everything needed to continue exactly: tensors, numbers, lists (``torch.save``-able,
        loadable with ``weights_only=True``). Written to the checkpoint file at once, so tensors
        may be the live ones (no copy of a large replay memory is needed)."""

    def load_state_dict(self, state: dict[str, Any]) -> None: ...

    def memory_bytes_per_run(self) -> int:
        """Bytes each run holds (replay and networks); where runs differ, the largest run's."""

    def memory_bytes_of(self, run: int) -> int:
        """Optional: run ``run``'s own bytes, as its result file's ``memory_bytes.learner_per_run``
        records them, for a learner whose runs differ (Empathic DQN: a run with ``Q_emp`` holds
        twice the networks of one without). A run's figure must not depend on which runs share
        its ensemble; without this method every run records :meth:`memory_bytes_per_run`."""

    @classmethod
    def check_memory(cls, settings: Sequence[Any], obs_size: int, num_actions: int, device: str, *, num_others: int) -> None:
        """Optional: raise ``ValueError`` (stating how much is needed and how much there is) when
        ``K = len(settings)`` runs would not fit in the memory of ``device``, from the settings
        alone, before anything is allocated (see :func:`empathy_zoo.limits.check_memory`). The
        trainer asks it for every ensemble of a sweep before the first one trains (without it,
        memory is not checked up front)."""

    def replay_bytes_per_run(self) -> int:
        """Optional: the part of :meth:`memory_bytes_per_run` that is each run's replay memory, as
        the result file's ``memory.replay_per_run`` reports it (0 without this method)."""

    def replay_bytes_of(self, run: int) -> int:
        """Optional: run ``run``'s own replay bytes, as its result file's ``memory_bytes.replay_per_run``
        records them, for a learner whose runs' memories differ (Empathic DQN: a run that prices
        costs keeps a cost column, :meth:`price_costs`); without it every run records
        :meth:`replay_bytes_per_run`."""

    def price_costs(self, runs: Sequence[bool]) -> None:
        """Optional: called once before training (before a checkpoint is loaded) where a run's
        reward transform prices costs when they are sampled (``priced_at_sample``,
        :class:`agents.rewards.PricedTransform`; ``runs`` says which runs' do): from then on every
        :class:`StepBatch` carries ``costs`` and ``prices``; the learner stores each step's cost
        beside its reward and trains on ``reward − price·cost`` with each run's price at the time
        of the update (the latest ``prices``). A learner without it cannot train such a method (the
        trainer refuses it, naming the method)."""

    def check_observation_range(self, low: float, high: float) -> None:
        """Optional: raise ``ValueError`` if observations with values in ``[low, high]`` (the
        environment's range, told once before training) are ones the learner cannot take, e.g.
        because its replay memory could not store them exactly (without this method, any range is
        taken)."""

    def agent_state(self, run: int) -> dict[str, Any]:
        """Optional: run ``run``'s trained agent, kept after training as its agent file
        (:mod:`empathy_zoo.agent_file`; a learner without it trains as well, and keeps no agent).

        Plain data: ``{"heads": {name: [W₁, b₁, …, Wₙ, bₙ]}, "acting": name}``: every value head the
        method has (Empathic DQN: ``"q"`` and ``"q_emp"``), each an MLP with ReLU between its
        layers, as float32 tensors or numpy arrays ``W: (in, out)`` (applied as ``x·W + b``) and
        ``b: (out,)``; ``acting`` names the head whose largest value (the first, as ``argmax``) is
        the greedy action. No replay memory or optimiser; tensors may be live (they are copied).
        A learner whose agent is a library's model offers ``save_agent(run, file)`` instead, which
        writes the library's own format (:class:`baselines.sb3.SB3Learner`)."""


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
    harmed: Empathic DQN puts the robot's own continuation in its place, SPEC §4) and ``other_swapped`` is
    zeros. The paper's swap is omniscient (seeing through walls is its future work)."""
    label: Callable[..., str] | None = None
    """Display name of a run from its settings (defaults to the name). A label that takes two
    arguments is also given the run's reward transform and shows its fields itself; to any other,
    the fields a run sets to other values than the method's are appended, as
    ``"DQN + inequity aversion (disadvantageous=0.3)"`` (a field named like a setting as
    ``reward.<field>=…``; :meth:`display_name`)."""
    description: str = ""
    """One line for ``empathy-zoo methods``."""
    family: str | None = None
    """The algorithm its runs are a case of, as the result file's description records it
    (``"empathic_dqn"``, ``"dqn"``, ``"sb3"``, a plug-in's own; ``None``: the method's name)."""
    target: str | None = None
    """The empathic target it learns, as :mod:`empathy_zoo.reference` names its rules
    (``"golden"``: Empathic DQN's, plain DQN at β = 1; ``"silver"``: the silver rule's); the
    leaderboard draws the exact reference beside its Coexistence runs on the environment's
    reward. ``None``: none."""
    dqn_reference: bool = False
    """Its runs on the environment's reward (no reward transform), at β = 1 where its settings
    have a β, are plain DQN: the reference the leaderboard compares every other method with."""
    identical_to: Mapping[str, tuple[str, str]] = field(default_factory=dict)
    """``{environment: (method, why)}``: on that environment, at its defaults, this method's runs
    are by construction those of the other registered method, seed for seed (Be Considerate's on
    Sharing are DQN's), so a table may mark the row as that method's."""

    def describe(self, settings: Any, reward: RewardTransform | None) -> dict[str, Any]:
        """What a run of this method with ``settings`` and ``reward`` (its transform, as
        :meth:`make_reward` gives it) is, as plain JSON data: the result file's
        ``config.description``, which the leaderboard reads instead of the method's name
        (:mod:`empathy_zoo.method_description` documents the fields). :attr:`family`,
        :attr:`target`, :attr:`dqn_reference` and :attr:`in_view_only` come from this entry;
        ``selfishness``, ``gamma`` and ``exploration`` from ``settings.describe()`` where the
        settings class has one (:class:`agents.settings.EmpathicDQNSettings` does), else ``None``.
        An unknown or malformed field raises ``ValueError`` naming the method."""
        described = settings.describe() if callable(getattr(settings, "describe", None)) else {}
        unknown = sorted(set(described) - set(SETTINGS_DESCRIBE))
        if unknown:
            raise ValueError(
                f"method {self.name!r}: its settings describe {unknown}; a settings class describes only "
                f"{list(SETTINGS_DESCRIBE)}"
            )
        description = default_description(self.family or self.name)
        description |= {"target": self.target, "in_view_only": self.in_view_only, **described}
        description["reward"] = transform_config(reward)
        description["dqn_reference"] = self.dqn_reference and reward is None and description["selfishness"] in (None, 1.0)
        try:
            return check_description(description)
        except ValueError as error:
            raise ValueError(f"method {self.name!r}: {error}") from None

    def make_settings(self, overrides: dict[str, Any]) -> Any:
        """The method's settings with ``overrides``; overriding a preset raises ``ValueError``, as
        does a value the result reader would refuse in the run's ``config.settings``
        (:func:`empathy_zoo.setting_values.check_recorded_settings`, the reader's own rule: an int in
        ``[0, MAX_SETTING]``, a finite float of magnitude at most ``MAX_SETTING``, ...), checked in
        ``overrides`` before the settings class sees them and in the settings it makes (their
        record, :func:`empathy_zoo.setting_values.settings_record`) after."""
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
        check_recorded_settings(self.settings, overrides)  # (the reader's rule, before the class computes with them)
        settings = self.settings(**{**overrides, **self.preset})
        check_recorded_settings(self.settings, settings_record(settings))  # (and its defaults, as recorded)
        return settings

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
