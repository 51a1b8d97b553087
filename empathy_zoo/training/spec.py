"""What one training run is: :class:`RunSpec`, its id, and which runs can share an ensemble."""

from __future__ import annotations

import hashlib
import json
from collections.abc import Iterable, Mapping
from dataclasses import asdict, dataclass, field
from typing import Any

from agents.base import Method
from agents.rewards import transform_config
from baselines.registry import get_method
from empathy_zoo.engine.base import check_choice, check_env_arguments
from empathy_zoo.environments import ENGINES, default_policies
from empathy_zoo.names import check_path_name
from empathy_zoo.policies import PolicyEntry, entry_label, policy_entry

__all__ = ["RunSpec", "group_specs"]


@dataclass(frozen=True)
class RunSpec:
    """One training run. Runs are identified by everything here; the seed is the only
    difference between the repetitions of an experiment."""

    env: str = "coexistence_v0"
    """Environment name (``coexistence_v0`` or ``sharing_v0``)."""
    method: str = "empathic_dqn"
    """Registered learning method (see ``empathy-zoo methods``) or ``package.module:NAME``."""
    settings: Mapping[str, Any] = field(default_factory=dict)
    """Overrides of the method's settings (e.g. ``{"selfishness": 0.5}``)."""
    reward: Mapping[str, Any] = field(default_factory=dict)
    """Overrides of the fields of the method's reward transform (e.g. ``{"penalty": -10.0}`` for
    ``dqn_harm_penalty``); recorded, with the fields left at their defaults, in ``config.reward``."""
    seed: int = 0
    """Seed of the run (networks, exploration, replay sampling, environments)."""
    steps: int = 1_000_000
    """Env steps to train for."""
    eval_interval: int = 50_000
    """Env steps between greedy evaluations (there is always one at the end)."""
    eval_episodes: int = 10
    """Episodes per greedy evaluation (ε = 0, fixed start seeds)."""
    fixed: Mapping[str, PolicyEntry] | None = None
    """Fixed agents and their policies: a name or ``package.module:ClassName``, or
    ``{"policy": name, **arguments}`` to build it with keyword arguments; ``None`` = the paper's."""
    env_kwargs: Mapping[str, Any] = field(default_factory=dict)
    """Environment arguments (``size``, ``view``, ``max_cycles``, and the environment's own, e.g.
    Sharing's ``start`` and ``inventory_encoding``)."""
    label: str | None = None
    """Display name in tables; ``None`` = the method's own label."""
    variant: str | None = None
    """Name of an environment variant (a sweep's env key), shown in tables; ``None`` = ``env``."""

    def __post_init__(self) -> None:
        if self.env not in ENGINES:
            raise ValueError(f"unknown environment {self.env!r}; registered: {sorted(ENGINES)}")
        if self.variant is not None:
            check_path_name(self.variant, "variant")
        if not isinstance(self.seed, int) or self.seed < 0:
            raise ValueError(f"seed must be a non-negative int, got {self.seed!r}")
        for name in ("steps", "eval_interval", "eval_episodes"):
            value = getattr(self, name)
            if not isinstance(value, int) or value < 1:
                raise ValueError(f"{name} must be a positive int, got {value!r}")
        engine = ENGINES[self.env]
        check_env_arguments(engine, self.env_kwargs, ValueError)
        for name, allowed in engine.extra_arguments.items():
            if name in self.env_kwargs:
                check_choice(name, self.env_kwargs[name], allowed)
        self.method_settings()  # validates method and settings
        if not isinstance(self.reward, Mapping):
            raise ValueError(f"reward must be a table {{field: value}} of the reward transform's fields, got {self.reward!r}")
        self.reward_transform()  # validates the reward transform's fields
        if self.fixed is not None:
            if not isinstance(self.fixed, Mapping):
                raise ValueError(f"fixed must be a table {{agent: policy}}, got {self.fixed!r}")
            entries = {}
            for agent, entry in self.fixed.items():
                try:
                    entries[agent] = policy_entry(entry)
                except ValueError as error:
                    raise ValueError(f"fixed policy of {agent!r}: {error}") from None
            object.__setattr__(self, "fixed", entries)  # one form: an entry without arguments is its name

    # ------------------------------------------------------------------ derived
    def method_object(self) -> Method:
        return get_method(self.method)

    def method_settings(self) -> Any:
        return self.method_object().make_settings(dict(self.settings))

    def reward_transform(self) -> Any:
        """The reward transform this run trains with: the method's, with :attr:`reward` set
        (``None``: the environment's reward)."""
        return self.method_object().make_reward(dict(self.reward))

    def fixed_policies(self) -> dict[str, PolicyEntry]:
        """The fixed agents' policy entries (what :class:`~empathy_zoo.vector.VectorEnv` builds them from)."""
        policies: dict[str, PolicyEntry] = dict(default_policies(self.env, self.env_kwargs) if self.fixed is None else self.fixed)
        return policies

    def display_label(self) -> str:
        return self.label or self.method_object().display_name(self.method_settings(), self.reward_transform())

    def config(self) -> dict[str, Any]:
        """The full configuration, as written into the result file."""
        return {
            "env": self.env,
            "variant": self.variant or self.env,
            "env_kwargs": dict(self.env_kwargs),
            "fixed": {agent: entry_label(entry) for agent, entry in self.fixed_policies().items()},
            "method": self.method,
            "settings": asdict(self.method_settings()),
            "reward": transform_config(self.reward_transform()),
            "seed": self.seed,
            "steps": self.steps,
            "eval_interval": self.eval_interval,
            "eval_episodes": self.eval_episodes,
            "label": self.display_label(),
        }

    def experiment_hash(self) -> str:
        """Hash of everything but the seed (the runs of one experiment share it)."""
        config = self.config()
        del config["seed"]
        return hashlib.sha256(json.dumps(config, sort_keys=True, default=str).encode()).hexdigest()[:8]

    @property
    def run_id(self) -> str:
        """File-safe unique id: ``<variant>__<method>-<hash>__s<seed>``."""
        method = self.method.replace(":", "_").replace(".", "_")
        return f"{self.variant or self.env}__{method}-{self.experiment_hash()}__s{self.seed}"

    def ensemble_key(self) -> tuple:
        """Runs with equal keys can train in one lockstep ensemble."""
        method = self.method_object()
        return (
            self.env,
            json.dumps(dict(self.env_kwargs), sort_keys=True),
            json.dumps(self.fixed_policies(), sort_keys=True),
            method.learner,
            method.in_view_only,
            _shared(self.method_settings()),
            self.steps,
            self.eval_interval,
            self.eval_episodes,
        )


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
