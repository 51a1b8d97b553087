"""An evaluation file as one typed, frozen record: :class:`EvaluationResult`, what the held-out
section and ``empathy-zoo evaluate`` read.

:func:`empathy_zoo.evaluation_file.read_evaluation` checks a file once
(:func:`~empathy_zoo.evaluation_file.check_evaluation`) and gives it as a record made of that
checked document only (:meth:`EvaluationResult.from_checked`); :meth:`EvaluationResult.to_document`
gives the document back, field for field. Its tables are read-only mappings of plain values and
its per-episode values read-only numpy arrays (:mod:`empathy_zoo.record_parts`). The partners a
file names are policy labels, never resolved here: a record imports nothing a file names.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any

import numpy as np

from empathy_zoo.metrics import METRIC_NAMES
from empathy_zoo.record_parts import AgentRef, frozen_plain, listed, read_only_series, thawed

__all__ = ["ScenarioDefinition", "ScenarioSetDefinition", "ScenarioScores", "EvaluationResult"]


@dataclass(frozen=True)
class ScenarioDefinition:
    """A scenario of a set, as the set defines it (an entry of the file's ``scenario_set.scenarios``)."""

    name: str
    """The scenario's name."""
    reason: str
    """What it tests, one line."""
    env_kwargs: Mapping[str, int | str]
    """Its environment arguments, laid over the run's when played."""
    fixed: Mapping[str, str]
    """``{agent: policy label}`` of its partners."""

    @classmethod
    def from_checked(cls, entry: Mapping[str, Any]) -> ScenarioDefinition:
        """The record of a checked scenario definition."""
        return cls(entry["name"], entry["reason"], frozen_plain(entry["env_kwargs"]), frozen_plain(entry["fixed"]))

    def to_document(self) -> dict[str, Any]:
        """The definition as the file holds it."""
        return {"name": self.name, "reason": self.reason, "env_kwargs": thawed(self.env_kwargs), "fixed": thawed(self.fixed)}


@dataclass(frozen=True)
class ScenarioSetDefinition:
    """The scenario set an evaluation played (the file's ``scenario_set``): equal to another when
    every field is (two files of one set must hold the same definition)."""

    name: str
    """The set's name (and the folder of its evaluation files)."""
    env: str
    """The environment its scenarios are for."""
    description: str | None
    """One line saying what the set is; ``None`` where the file gives none (``""`` where it gives an empty one)."""
    scenarios: tuple[ScenarioDefinition, ...]
    """Its scenarios, in order."""

    @classmethod
    def from_checked(cls, definition: Mapping[str, Any]) -> ScenarioSetDefinition:
        """The record of a checked ``scenario_set``."""
        scenarios = tuple(ScenarioDefinition.from_checked(entry) for entry in definition["scenarios"])
        return cls(definition["name"], definition["env"], definition.get("description"), scenarios)

    def to_document(self) -> dict[str, Any]:
        """The definition as the file holds it."""
        described = {} if self.description is None else {"description": self.description}
        return {"name": self.name, "env": self.env, **described, "scenarios": [s.to_document() for s in self.scenarios]}


@dataclass(frozen=True, eq=False)
class ScenarioScores:
    """What an agent scored in one scenario (an entry of the file's ``scenarios``)."""

    name: str
    """The scenario's name (:data:`~empathy_zoo.evaluation_file.TRAINED_WITH` for the run's own partners)."""
    reason: str
    """What it tests, one line."""
    held_out: bool
    """Whether it is another world than the run's own (its partners or arguments)."""
    env_kwargs: Mapping[str, int | str]
    """The environment arguments played."""
    fixed: Mapping[str, str]
    """``{agent: policy label}`` of the partners played."""
    metrics: Mapping[str, np.ndarray]
    """Every metric of :data:`~empathy_zoo.metrics.METRIC_NAMES`, one value per episode."""

    @classmethod
    def from_checked(cls, entry: Mapping[str, Any]) -> ScenarioScores:
        """The record of a checked entry of ``scenarios``."""
        metrics = MappingProxyType({name: read_only_series(entry["metrics"][name]) for name in METRIC_NAMES})
        return cls(
            entry["name"],
            entry["reason"],
            entry["held_out"],
            frozen_plain(entry["env_kwargs"]),
            frozen_plain(entry["fixed"]),
            metrics,
        )

    def to_document(self) -> dict[str, Any]:
        """The entry as the file holds it."""
        return {
            "name": self.name,
            "reason": self.reason,
            "held_out": self.held_out,
            "env_kwargs": thawed(self.env_kwargs),
            "fixed": thawed(self.fixed),
            "metrics": {name: listed(series) for name, series in self.metrics.items()},
        }


_FIELDS = (
    "format",
    "schema",
    "version",
    "run_id",
    "env",
    "variant",
    "method",
    "method_label",
    "seed",
    "agent",
    "scenario_set",
    "episodes",
    "stream",
    "scenarios",
)


@dataclass(frozen=True, eq=False)
class EvaluationResult:
    """One trained agent scored beside held-out partners, as its evaluation file records it
    (docs/formats.md, "The evaluation file"), checked. Records are compared by identity;
    :meth:`to_document` compares by value."""

    format: str
    """:data:`~empathy_zoo.evaluation_file.FORMAT`."""
    schema: int
    """:data:`~empathy_zoo.evaluation_file.SCHEMA`."""
    run_id: str
    """The run evaluated (its result file is ``<run id>.json``)."""
    env: str
    """The run's environment."""
    variant: str | None
    """The run's variant; ``None`` where the file leaves it out (the environment's name)."""
    method: str
    """The run's method (never imported)."""
    method_label: str
    """The run's label."""
    seed: int
    """The run's seed."""
    agent: AgentRef
    """The agent file evaluated (the run's result file records the same)."""
    scenario_set: ScenarioSetDefinition
    """The set played, as its file defined it."""
    episodes: int
    """Greedy episodes per scenario."""
    stream: int
    """The random stream of the start seeds (:data:`~empathy_zoo.evaluation_file.STREAM`)."""
    scenarios: tuple[ScenarioScores, ...]
    """What the agent scored in each scenario played, its own partners' first."""
    version: str | None = None
    """The empathy-zoo that wrote it; ``None`` where the file leaves it out."""
    fields: tuple[str, ...] = ()
    """The file's fields, in its order (what :meth:`to_document` gives back)."""

    @classmethod
    def from_checked(cls, document: Mapping[str, Any]) -> EvaluationResult:
        """The record of ``document``, which :func:`~empathy_zoo.evaluation_file.check_evaluation`
        gave (it is not checked again: only a checked document may be given)."""
        return cls(
            format=document["format"],
            schema=document["schema"],
            run_id=document["run_id"],
            env=document["env"],
            variant=document.get("variant"),
            method=document["method"],
            method_label=document["method_label"],
            seed=document["seed"],
            agent=AgentRef.from_checked(document["agent"]),
            scenario_set=ScenarioSetDefinition.from_checked(document["scenario_set"]),
            episodes=document["episodes"],
            stream=document["stream"],
            scenarios=tuple(ScenarioScores.from_checked(entry) for entry in document["scenarios"]),
            version=document.get("version"),
            fields=tuple(document),
        )

    def to_document(self) -> dict[str, Any]:
        """The checked document this record was made of, field for field."""
        values = {name: getattr(self, name) for name in _FIELDS}
        values |= {
            "agent": self.agent.to_document(),
            "scenario_set": self.scenario_set.to_document(),
            "scenarios": [entry.to_document() for entry in self.scenarios],
        }
        return {name: values[name] for name in self.fields}

    def scenario(self, name: str) -> ScenarioScores | None:
        """The scores of the scenario ``name`` (``None``: it was not played)."""
        return next((entry for entry in self.scenarios if entry.name == name), None)
