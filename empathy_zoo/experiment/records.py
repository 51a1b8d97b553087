"""A run's result as one typed, frozen record: :class:`RunResult`, what every reader works on.

A result file is read once, through the one checker (:func:`empathy_zoo.experiment.result_reader.check_result`,
which upgrades files of older schemas), and only a document that checker accepted becomes a record
(:meth:`RunResult.from_checked`); :meth:`RunResult.to_document` gives that document back, field for
field. Nothing in a record can be changed: its tables are read-only mappings of plain values
(objects, arrays as tuples, strings, numbers, booleans, ``None``), and its per-episode series are
read-only numpy arrays (:mod:`empathy_zoo.record_parts`), so a leaderboard holds a file in about the
memory its numbers take (a list of Python floats takes four times that, and the objects around it
more). A relabelled run (a directory's prefix, a budget, a row shown as DQN) is a new record,
:func:`dataclasses.replace`.

A series is ``int64`` where the file writes whole numbers as integers (training's counts and end
steps: every value an integer an ``int64`` holds) and ``float64`` otherwise (a JSON number with a
fraction or an exponent is a double, read exactly; a greedy evaluation writes its counts so too).
So every number is the one the file holds, and :meth:`~RunResult.to_document` writes it back as it
was written.

A record is inert data. Its config names its method (``run.method``; a ``package.module:NAME``
plug-in, say) but the record never resolves it: building the run's
:class:`~empathy_zoo.experiment.model.RunSpec` would import the code a file names, and a file read
from elsewhere must not make the suite import anything. No reader needs the spec of a finished run,
so the record offers none.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any

import numpy as np

from empathy_zoo.metrics import METRIC_NAMES
from empathy_zoo.record_parts import AgentRef, PlainTable, empty_table, frozen_plain, listed, read_only_series, thawed
from empathy_zoo.result_file import KNOWN_FIELDS, PRICE_COLUMN, experiment_of

__all__ = [
    "PlainTable",
    "frozen_plain",
    "thawed",
    "read_only_series",
    "AgentRef",
    "RunConfig",
    "TrainRecord",
    "EvalPoint",
    "RunResult",
]

END_STEP = "episode_end_step"
"""The training column of the env step each episode ended at."""


def _table(values: Mapping[str, Any] | None) -> dict[str, Any] | None:
    return None if values is None else dict(values)


_CONFIG_FIELDS = (
    "env",
    "variant",
    "env_kwargs",
    "fixed",
    "method",
    "settings",
    "reward",
    "description",
    "seed",
    "steps",
    "eval_interval",
    "eval_episodes",
    "label",
)


@dataclass(frozen=True)
class RunConfig:
    """What a run was built with (the result file's ``config``), as checked values."""

    settings: PlainTable
    """The method's settings, as the file records them (a registered method's checked by its class)."""
    env_kwargs: Mapping[str, int | str]
    """The environment's arguments the run set (the others at their defaults)."""
    fixed: Mapping[str, str]
    """``{agent: policy label}`` of the fixed (non-learning) agents."""
    description: PlainTable
    """What the run was, as its method describes it (:mod:`empathy_zoo.method_description`)."""
    reward: PlainTable | None
    """The reward transform the method trained on (``name`` and its fields); ``None``: the environment's reward."""
    env: str | None = None
    """The environment (the result's ``env``; ``None`` where the config does not repeat it)."""
    variant: str | None = None
    """The sweep's env key (the result's ``variant``), where recorded."""
    method: str | None = None
    """The method (the result's ``method``), where recorded."""
    label: str | None = None
    """The run's label (the result's ``method_label``), where recorded."""
    seed: int | None = None
    """The seed (the result's ``seed``), where recorded."""
    steps: int | None = None
    """Training env steps (the result's ``steps``), where recorded."""
    eval_interval: int | None = None
    """Env steps between greedy evaluations; ``None`` in files made before it was recorded."""
    eval_episodes: int | None = None
    """Episodes per greedy evaluation; ``None`` in files made before it was recorded."""
    extra: PlainTable = field(default_factory=empty_table)
    """Fields of ``config`` this record does not name, kept as read."""
    fields: tuple[str, ...] = ()
    """The fields of ``config`` in the file, in its order (what :meth:`to_document` gives back)."""

    @classmethod
    def from_checked(cls, config: Mapping[str, Any]) -> RunConfig:
        """The record of a checked ``config`` table."""
        reward = config.get("reward")
        return cls(
            settings=frozen_plain(config["settings"]),
            env_kwargs=frozen_plain(config["env_kwargs"]),
            fixed=frozen_plain(config["fixed"]),
            description=frozen_plain(config["description"]),
            reward=None if reward is None else frozen_plain(reward),
            env=config.get("env"),
            variant=config.get("variant"),
            method=config.get("method"),
            label=config.get("label"),
            seed=config.get("seed"),
            steps=config.get("steps"),
            eval_interval=config.get("eval_interval"),
            eval_episodes=config.get("eval_episodes"),
            extra=frozen_plain({key: value for key, value in config.items() if key not in _CONFIG_FIELDS}),
            fields=tuple(config),
        )

    def to_document(self) -> dict[str, Any]:
        """The ``config`` table as the checked document holds it."""
        values = {name: thawed(getattr(self, name)) for name in _CONFIG_FIELDS} | thawed(self.extra)
        return {name: values[name] for name in self.fields}

    @property
    def reward_name(self) -> str | None:
        """The name of the reward transform (``None``: the environment's reward)."""
        return None if self.reward is None else str(self.reward["name"])


def _equal_series(first: Mapping[str, np.ndarray], second: Mapping[str, np.ndarray]) -> bool:
    """The same columns, value for value (an integer equals the float of the same value)."""
    return first.keys() == second.keys() and all(np.array_equal(first[name], second[name]) for name in first)


@dataclass(frozen=True, eq=False)
class TrainRecord:
    """A run's training episodes (the result file's ``train``): one value per episode in each column."""

    episode_end_step: np.ndarray
    """The env step each episode ended at, increasing."""
    metrics: Mapping[str, np.ndarray]
    """Every metric of :data:`~empathy_zoo.metrics.METRIC_NAMES`, one value per episode."""
    price: np.ndarray | None = None
    """The price of one unit of cost after each episode (:data:`~empathy_zoo.result_file.PRICE_COLUMN`,
    the Lagrangian method's λ), for a method that prices its cost; else ``None``."""

    @classmethod
    def from_checked(cls, train: Mapping[str, Any]) -> TrainRecord:
        """The record of a checked ``train`` table."""
        price = train.get(PRICE_COLUMN)
        return cls(
            read_only_series(train[END_STEP]),
            MappingProxyType({name: read_only_series(train[name]) for name in METRIC_NAMES}),
            None if price is None else read_only_series(price),
        )

    @property
    def episodes(self) -> int:
        """How many training episodes ended."""
        return int(self.episode_end_step.size)

    def columns(self) -> dict[str, np.ndarray]:
        """Every column by its name in the file: ``episode_end_step``, the metrics, and the price where recorded."""
        return {END_STEP: self.episode_end_step, **self.metrics, **({} if self.price is None else {PRICE_COLUMN: self.price})}

    def column(self, name: str) -> np.ndarray:
        """The column ``name`` (``KeyError`` for one the run did not record)."""
        return self.columns()[name]

    def __eq__(self, other: object) -> bool:
        """The same columns, value for value."""
        return isinstance(other, TrainRecord) and _equal_series(self.columns(), other.columns())

    __hash__ = None  # type: ignore[assignment]  # (equal by value, and mutable arrays are no key)

    def to_document(self) -> dict[str, list[Any]]:
        """The ``train`` table as the file holds it."""
        return {name: listed(series) for name, series in self.columns().items()}


@dataclass(frozen=True, eq=False)
class EvalPoint:
    """One greedy evaluation of a run (an entry of the result file's ``eval``)."""

    step: int
    """The training env step it was made at."""
    metrics: Mapping[str, np.ndarray]
    """Every metric of :data:`~empathy_zoo.metrics.METRIC_NAMES`, one value per greedy episode."""

    @classmethod
    def from_checked(cls, entry: Mapping[str, Any]) -> EvalPoint:
        """The record of a checked entry of ``eval``."""
        return cls(int(entry["step"]), MappingProxyType({name: read_only_series(entry[name]) for name in METRIC_NAMES}))

    @property
    def episodes(self) -> int:
        """How many greedy episodes it played."""
        return int(next(iter(self.metrics.values())).size) if self.metrics else 0

    def __eq__(self, other: object) -> bool:
        """The same step and the same values."""
        return isinstance(other, EvalPoint) and self.step == other.step and _equal_series(self.metrics, other.metrics)

    __hash__ = None  # type: ignore[assignment]

    def to_document(self) -> dict[str, Any]:
        """The entry as the file holds it."""
        return {"step": self.step, **{name: listed(series) for name, series in self.metrics.items()}}


@dataclass(frozen=True, eq=False)
class RunResult:
    """One finished run, as its result file records it (docs/formats.md), checked.

    Records are compared by identity (two reads of one file are two records); :meth:`to_document`
    compares by value."""

    run_id: str
    """``<variant>__<method>-<hash>__s<seed>``: the run's identity, and its file's name."""
    env: str
    """The registered environment the run trained in."""
    variant: str | None
    """The env key of its sweep (``coexistence_3cats``); ``None``: the environment's name."""
    method: str
    """The registered method's name, or the ``package.module:NAME`` of a plug-in (never imported)."""
    method_label: str
    """The run's label, as its rows show it (a reader may relabel a record: :func:`dataclasses.replace`)."""
    seed: int
    """The run's seed."""
    steps: int
    """Training env steps."""
    config: RunConfig
    """What the run was built with."""
    train: TrainRecord
    """The training episodes."""
    eval: tuple[EvalPoint, ...]
    """The greedy evaluations, by step."""
    schema: int
    """The result-file schema (:data:`~empathy_zoo.result_file.SCHEMA`: files of older ones are upgraded when read)."""
    memory_bytes: Mapping[str, int] | None = None
    """``{part: bytes}`` the learner held; ``None`` where the file does not record it."""
    wall_time_s: float | None = None
    """Seconds the run took; ``None`` where not recorded."""
    version: str | None = None
    """The empathy-zoo version that made it; ``None`` where not recorded."""
    commit: str | None = None
    """The git commit of the code that made it; ``None`` where not recorded (or unknown)."""
    plugin_sha256: Mapping[str, str | None] | None = None
    """``{module: SHA-256 of its source}`` of the plug-ins it ran; ``None`` in files older than it."""
    update_kernel: str | None = None
    """The update kernel its learner used (``numba``, ``torch``); ``None`` where it had no choice or it is not recorded."""
    agent: AgentRef | None = None
    """The agent file kept beside the result file; ``None`` where the method keeps none."""
    created: str | None = None
    """When the file was written (ISO 8601); ``None`` where not recorded."""
    extra: PlainTable = field(default_factory=empty_table)
    """Top-level fields this record does not name, kept as read."""
    fields: tuple[str, ...] = ()
    """The file's top-level fields, in its order (what :meth:`to_document` gives back)."""

    @classmethod
    def from_checked(cls, document: Mapping[str, Any]) -> RunResult:
        """The record of ``document``, which :func:`~empathy_zoo.experiment.result_reader.check_result`
        gave (it is not checked again: only a checked document may be given)."""
        agent = document.get("agent")
        memory = document.get("memory_bytes")
        plugins = document.get("plugin_sha256")
        return cls(
            run_id=document["run_id"],
            env=document["env"],
            variant=document.get("variant"),
            method=document["method"],
            method_label=document["method_label"],
            seed=document["seed"],
            steps=document["steps"],
            config=RunConfig.from_checked(document["config"]),
            train=TrainRecord.from_checked(document["train"]),
            eval=tuple(EvalPoint.from_checked(entry) for entry in document["eval"]),
            schema=document["schema"],
            memory_bytes=None if memory is None else MappingProxyType(dict(memory)),
            wall_time_s=document.get("wall_time_s"),
            version=document.get("version"),
            commit=document.get("commit"),
            plugin_sha256=None if plugins is None else MappingProxyType(dict(plugins)),
            update_kernel=document.get("update_kernel"),
            agent=None if agent is None else AgentRef.from_checked(agent),
            created=document.get("created"),
            extra=frozen_plain({key: value for key, value in document.items() if key not in KNOWN_FIELDS}),
            fields=tuple(document),
        )

    def to_document(self, *, series: bool = True) -> dict[str, Any]:
        """The checked document this record was made of, field for field (a JSON file of it reads
        back as this record); without ``series``, all of it but ``train`` and ``eval`` (what a
        reader that compares a run's identity, world or agent with another file's needs)."""
        values: dict[str, Any] = {
            "schema": self.schema,
            "run_id": self.run_id,
            "env": self.env,
            "variant": self.variant,
            "method": self.method,
            "method_label": self.method_label,
            "seed": self.seed,
            "config": self.config.to_document(),
            "steps": self.steps,
            "train": self.train.to_document() if series else None,
            "eval": [entry.to_document() for entry in self.eval] if series else None,
            "memory_bytes": _table(self.memory_bytes),
            "wall_time_s": self.wall_time_s,
            "version": self.version,
            "commit": self.commit,
            "plugin_sha256": _table(self.plugin_sha256),
            "update_kernel": self.update_kernel,
            "agent": None if self.agent is None else self.agent.to_document(),
            "created": self.created,
            **thawed(self.extra),
        }
        return {name: values[name] for name in self.fields if series or name not in ("train", "eval")}

    @property
    def table_env(self) -> str:
        """The env a run is tabled under: its variant (a sweep's env key) if any, else its env."""
        return self.variant or self.env

    @property
    def experiment(self) -> str:
        """The run id without its seed: the runs of one experiment share it."""
        return experiment_of(self.run_id)

    @property
    def last_eval(self) -> EvalPoint | None:
        """The greedy evaluation of the latest step (``None``: the run made none)."""
        return max(self.eval, key=lambda entry: entry.step) if self.eval else None

    def eval_steps(self) -> Iterator[int]:
        """The steps of its greedy evaluations, in the file's order."""
        return (entry.step for entry in self.eval)
