"""What an experiment is, as typed, frozen objects resolved once: an environment variant, a
method entry, a run budget and, from them and a seed, one :class:`RunSpec`.

Everything the command line, the sweep files, the trainer and the result files know about a run
is read from these objects; nothing re-derives it. A :class:`RunSpec` is built from resolved
objects (:meth:`RunSpec.of` builds them from plain keyword arguments, as a Python user or a
checkpoint's list of runs gives them); its run id hashes :meth:`RunSpec.config`, the record the
result file keeps.
"""

from __future__ import annotations

import json
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field, fields
from typing import Any

from agents.base import Method
from agents.rewards import RewardTransform, transform_config
from baselines.registry import get_method
from empathy_zoo import run_ids
from empathy_zoo.engine.arguments import check_choice, check_env_arguments
from empathy_zoo.environments import DEFAULT_ENVIRONMENT, ENGINES, default_policies
from empathy_zoo.limits import MAX_EVAL_EPISODES, MAX_EVALUATIONS, MAX_SEED, MAX_STEPS, check_at_most
from empathy_zoo.names import check_label, check_path_name
from empathy_zoo.policies import PolicyEntry, entry_label, make_policy, policy_entry
from empathy_zoo.setting_values import settings_record

__all__ = ["DEFAULT_METHOD", "Budget", "EnvVariant", "MethodEntry", "RunSpec", "group_specs"]

DEFAULT_METHOD = "empathic_dqn"
"""The method a run trains when none is named."""


@dataclass(frozen=True)
class EnvVariant:
    """An environment with its arguments and fixed agents; a sweep's ``[envs.<variant>]`` table."""

    env: str = DEFAULT_ENVIRONMENT
    """Environment name (``coexistence_v0``, ``sharing_v0``, any of :data:`~empathy_zoo.environments.ENVIRONMENT_TABLE`;
    see ``empathy-zoo envs``)."""
    kwargs: Mapping[str, Any] = field(default_factory=dict)
    """Environment arguments (``size``, ``view``, ``max_cycles`` and the environment's own, e.g.
    Sharing's ``start`` and ``inventory_encoding``, Coexistence's ``num_cats``)."""
    fixed: Mapping[str, PolicyEntry] | None = None
    """Fixed agents and their policies: a name or ``package.module:ClassName``, or
    ``{"policy": name, **arguments}``; ``None`` = the environment's defaults (the paper's)."""
    name: str | None = None
    """The variant's name in run ids and tables; ``None`` = :attr:`env`."""

    def __post_init__(self) -> None:
        if self.env not in ENGINES:
            raise ValueError(f"unknown environment {self.env!r}; registered: {sorted(ENGINES)}")
        if self.name is not None:
            check_path_name(self.name, "variant")
        if not isinstance(self.kwargs, Mapping):
            raise ValueError(f"env_kwargs must be a table {{argument: value}}, got {self.kwargs!r}")
        engine = ENGINES[self.env]
        check_env_arguments(engine, self.kwargs, ValueError)
        for name, allowed in engine.extra_arguments.items():
            if name in self.kwargs:
                check_choice(name, self.kwargs[name], allowed)
        agents = engine(1, **self.kwargs).agents  # the grid arguments and agent counts, checked by the engine
        if self.fixed is not None:
            if not isinstance(self.fixed, Mapping):
                raise ValueError(f"fixed must be a table {{agent: policy}}, got {self.fixed!r}")
            unknown = [agent for agent in self.fixed if agent not in agents]
            if unknown:
                raise ValueError(f"fixed: unknown agent(s) {unknown}; agents of {self.env}: {list(agents)}")
            entries = {}
            for agent, entry in self.fixed.items():
                try:
                    entries[agent] = policy_entry(entry)
                    make_policy(entries[agent])
                except ValueError as error:
                    raise ValueError(f"fixed.{agent}: {error}") from None
            object.__setattr__(self, "fixed", entries)  # one form: an entry without arguments is its name
        object.__setattr__(self, "kwargs", dict(self.kwargs))
        fixed = self.fixed_policies()
        learners = [agent for agent in agents if agent not in fixed]
        if len(learners) != 1:
            raise ValueError(
                f"a run needs exactly one learning agent, but {self.env} with fixed agents {sorted(fixed)} leaves "
                + (f"{len(learners)}: {learners}" if learners else "none")
                + f" (its agents: {list(agents)}); fix every agent but one (the learner, usually {agents[0]})"
            )

    @property
    def label(self) -> str:
        """The variant's name (the environment's when it has none of its own)."""
        return self.name or self.env

    def fixed_policies(self) -> dict[str, PolicyEntry]:
        """The fixed agents' policy entries (what :class:`~empathy_zoo.vector.VectorEnv` builds them from)."""
        return dict(default_policies(self.env, self.kwargs) if self.fixed is None else self.fixed)


@dataclass(frozen=True)
class MethodEntry:
    """A learning method with an instance of its settings and of its reward transform."""

    name: str
    """The method as named (a registry name or ``package.module:NAME``): what run ids show."""
    method: Method
    """The registered method."""
    settings: Any
    """An instance of the method's settings dataclass."""
    reward: RewardTransform | None
    """The reward transform its runs train with (``None``: the environment's reward)."""
    label: str | None = None
    """Display name in tables; ``None`` = the method's own (:meth:`Method.display_name`). Either is
    a label the result-file reader accepts (:func:`empathy_zoo.names.check_label`), or the entry is
    refused when it is built."""

    def __post_init__(self) -> None:
        if self.label is not None:
            check_label(self.label, "label")
        else:
            check_label(self.display_label(), f"the label method {self.name!r} gives its runs")

    @classmethod
    def resolve(
        cls,
        name: str,
        settings: Mapping[str, Any] | None = None,
        reward: Mapping[str, Any] | None = None,
        label: str | None = None,
    ) -> MethodEntry:
        """The entry of method ``name`` with the settings and reward-transform fields given
        (``ValueError`` for an unknown method, setting or field, or a value its class refuses)."""
        if not isinstance(name, str):
            raise ValueError(f"method must be a name, got {name!r}")
        method = get_method(name)
        if settings is not None and not isinstance(settings, Mapping):
            raise ValueError(f"settings must be a table {{setting: value}}, got {settings!r}")
        if reward is not None and not isinstance(reward, Mapping):
            raise ValueError(f"reward must be a table {{field: value}} of the reward transform's fields, got {reward!r}")
        if label is not None and not isinstance(label, str):
            raise ValueError(f"label must be a string, got {label!r}")
        return cls(name, method, method.make_settings(dict(settings or {})), method.make_reward(dict(reward or {})), label)

    def display_label(self, shown: Iterable[str] = ()) -> str:
        """The name of the entry's runs in tables (the reward fields in ``shown`` shown even at
        their defaults)."""
        return self.label or self.method.display_name(self.settings, self.reward, tuple(shown))

    def changed_settings(self) -> dict[str, Any]:
        """The settings that differ from the method's defaults."""
        default = self.method.make_settings({})
        return {
            f.name: getattr(self.settings, f.name)
            for f in fields(self.settings)
            if getattr(self.settings, f.name) != getattr(default, f.name)
        }

    def changed_reward(self) -> dict[str, Any]:
        """The reward transform's fields that differ from the method's."""
        if self.reward is None or self.method.reward is None:
            return {}
        transform: Any = self.reward  # (a dataclass, as every reward transform is)
        return {
            f.name: getattr(self.reward, f.name)
            for f in fields(transform)
            if f.init and getattr(self.reward, f.name) != getattr(self.method.reward, f.name)
        }


@dataclass(frozen=True)
class Budget:
    """How long a run trains and how it is evaluated; a sweep's ``[sweep]`` table."""

    steps: int = 1_000_000
    """Env steps to train for (at most :data:`~empathy_zoo.limits.MAX_STEPS`)."""
    eval_interval: int = 50_000
    """Env steps between greedy evaluations (there is always one at the end; at most
    :data:`~empathy_zoo.limits.MAX_EVALUATIONS` of them)."""
    eval_episodes: int = 10
    """Episodes per greedy evaluation (ε = 0, fixed start seeds; at most
    :data:`~empathy_zoo.limits.MAX_EVAL_EPISODES`)."""

    def __post_init__(self) -> None:
        for name, bound in (("steps", MAX_STEPS), ("eval_interval", MAX_STEPS), ("eval_episodes", MAX_EVAL_EPISODES)):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or value < 1:
                raise ValueError(f"{name} must be a positive int, got {value!r}")
            check_at_most(name, value, bound)
        evaluations = -(-self.steps // self.eval_interval)
        if evaluations > MAX_EVALUATIONS:
            raise ValueError(
                f"steps={self.steps:,} with eval_interval={self.eval_interval:,} makes {evaluations:,} evaluations: a run "
                f"has at most {MAX_EVALUATIONS:,} evaluations (docs/limits.md); raise eval_interval"
            )


@dataclass(frozen=True)
class RunSpec:
    """One training run: an environment variant, a method entry, a budget and a seed. Runs are
    identified by everything here; the seed is the only difference between the repetitions of
    an experiment."""

    variant: EnvVariant
    """Where it trains."""
    entry: MethodEntry
    """What trains."""
    budget: Budget = Budget()
    """How long, and how it is evaluated."""
    seed: int = 0
    """Seed of the run (networks, exploration, replay sampling, environments)."""

    def __post_init__(self) -> None:
        if isinstance(self.seed, bool) or not isinstance(self.seed, int) or self.seed < 0:
            raise ValueError(f"seed must be a non-negative int, got {self.seed!r}")
        check_at_most("seed", self.seed, MAX_SEED, "2**63 - 1")

    @classmethod
    def of(
        cls,
        env: str = DEFAULT_ENVIRONMENT,
        method: str = DEFAULT_METHOD,
        settings: Mapping[str, Any] | None = None,
        reward: Mapping[str, Any] | None = None,
        seed: int = 0,
        steps: int = Budget.steps,
        eval_interval: int = Budget.eval_interval,
        eval_episodes: int = Budget.eval_episodes,
        fixed: Mapping[str, PolicyEntry] | None = None,
        env_kwargs: Mapping[str, Any] | None = None,
        label: str | None = None,
        variant: str | None = None,
    ) -> RunSpec:
        """A run from plain values: ``settings`` and ``reward`` override the method's settings and
        its reward transform's fields; the rest as :class:`EnvVariant`, :class:`MethodEntry` and
        :class:`Budget` take them."""
        return cls(
            EnvVariant(env, env_kwargs or {}, fixed, variant),
            MethodEntry.resolve(method, settings, reward, label),
            Budget(steps, eval_interval, eval_episodes),
            seed,
        )

    def request(self) -> dict[str, Any]:
        """The keyword arguments of :meth:`of` that rebuild this run (what a checkpoint's list of
        runs records)."""
        return {
            "env": self.env,
            "method": self.method,
            "settings": self.entry.changed_settings(),
            "reward": self.entry.changed_reward(),
            "seed": self.seed,
            "steps": self.steps,
            "eval_interval": self.budget.eval_interval,
            "eval_episodes": self.budget.eval_episodes,
            "fixed": None if self.variant.fixed is None else dict(self.variant.fixed),
            "env_kwargs": dict(self.variant.kwargs),
            "label": self.entry.label,
            "variant": self.variant.name,
        }

    def __reduce__(self) -> tuple[Any, ...]:
        # sent to worker processes as its request, resolved there again (a method's label may be a lambda)
        return (_rebuild, (self.request(),))

    # ------------------------------------------------------------------ what runs read
    @property
    def env(self) -> str:
        return self.variant.env

    @property
    def method(self) -> str:
        return self.entry.name

    @property
    def steps(self) -> int:
        return self.budget.steps

    @property
    def eval_interval(self) -> int:
        return self.budget.eval_interval

    @property
    def eval_episodes(self) -> int:
        return self.budget.eval_episodes

    @property
    def env_kwargs(self) -> dict[str, Any]:
        return dict(self.variant.kwargs)

    def method_object(self) -> Method:
        return self.entry.method

    def method_settings(self) -> Any:
        return self.entry.settings

    def reward_transform(self) -> RewardTransform | None:
        """The reward transform this run trains with (``None``: the environment's reward)."""
        return self.entry.reward

    def fixed_policies(self) -> dict[str, PolicyEntry]:
        return self.variant.fixed_policies()

    def display_label(self) -> str:
        return self.entry.display_label()

    def config(self) -> dict[str, Any]:
        """The full configuration, as written into the result file."""
        return {
            "env": self.env,
            "variant": self.variant.label,
            "env_kwargs": dict(self.variant.kwargs),
            "fixed": {agent: entry_label(entry) for agent, entry in self.fixed_policies().items()},
            "method": self.method,
            "settings": settings_record(self.entry.settings),
            "reward": transform_config(self.entry.reward),
            "description": self.entry.method.describe(self.entry.settings, self.entry.reward),
            "seed": self.seed,
            "steps": self.budget.steps,
            "eval_interval": self.budget.eval_interval,
            "eval_episodes": self.budget.eval_episodes,
            "label": self.display_label(),
        }

    def experiment_hash(self) -> str:
        """Hash of everything but the seed (the runs of one experiment share it)."""
        return run_ids.config_hash(self.config())

    @property
    def experiment_id(self) -> str:
        """What the runs of one experiment (all seeds) share: ``<variant>__<method>-<hash>``."""
        return run_ids.experiment_id(self.variant.label, self.method, self.config())

    @property
    def run_id(self) -> str:
        """File-safe unique id: ``<variant>__<method>-<hash>__s<seed>``."""
        return f"{self.experiment_id}__s{self.seed}"

    def ensemble_key(self) -> tuple:
        """Runs with equal keys can train in one lockstep ensemble."""
        method = self.entry.method
        return (
            self.env,
            json.dumps(dict(self.variant.kwargs), sort_keys=True),
            json.dumps(self.fixed_policies(), sort_keys=True),
            method.learner,
            method.in_view_only,
            _shared(self.entry.settings),
            self.budget,
        )


def _rebuild(request: dict[str, Any]) -> RunSpec:
    return RunSpec.of(**request)


def group_specs(specs: Iterable[RunSpec], max_parallel_runs: int) -> list[list[RunSpec]]:
    """Split runs into ensembles of at most ``max_parallel_runs`` compatible runs (stable order)."""
    if max_parallel_runs < 1:
        raise ValueError(f"max_parallel_runs must be positive, got {max_parallel_runs}")
    groups: dict[tuple, list[RunSpec]] = {}
    for spec in specs:
        groups.setdefault(spec.ensemble_key(), []).append(spec)
    chunks = []
    for members in groups.values():
        chunks += [members[i : i + max_parallel_runs] for i in range(0, len(members), max_parallel_runs)]
    return chunks


def _shared(settings: Any) -> Any:
    """What runs must share to train in one ensemble: ``settings.shared()`` when the settings class
    says which of its fields may differ between runs, else every setting (equal settings, any seed)."""
    return settings.shared() if hasattr(settings, "shared") else settings
