"""Scenario sets: the worlds a trained agent is evaluated in beside partners it never trained with.

A *scenario* is an environment variant a trained robot can still act in: other fixed agents (their
policies, with arguments, and their number) and other world arguments (the grid's ``size``,
``max_cycles``, Sharing's ``start``), with a one-line ``reason`` saying what it tests. A *scenario
set* is a TOML file of scenarios for one environment; one per environment ships here, its default
(:func:`shipped_sets`: ``coexistence_v0``, ``sharing_v0``, ``charger_v0``, ``vase_v0``,
``helping_v0``), and the opt-in ``coexistence_v0_noisy``, each written before any result was seen.
Each environment also ships a partner split's two held-out sets, ``<env>_validation`` and
``<env>_test`` (opt-in, ``--scenarios <env>_test``): populations of registered partners disjoint
from each other and from its training population (the ``populations`` profile), each set holding
the population and each member alone (docs/heldout.md, "Partner populations").
``empathy-zoo evaluate`` (:mod:`empathy_zoo.training.heldout`) plays every kept agent in every
scenario of its environment, and in :func:`trained_with`, the run's own partners and world.

Schema (docs/heldout.md)::

    [scenario_set]
    env = "coexistence_v0"           # the environment of every scenario (required)
    name = "my_partners"             # default: the file's stem; names evaluations/<name>/
    description = "..."              # optional, one line of printable text
    held_out = true                  # optional; only true (every scenario set is held out)

    [scenarios.cat_stays]            # one table per scenario; its key names it
    reason = "A cat that never moves: ..."        # required, one line
    fixed = { cat_0 = "stay" }       # the fixed agents: a policy name, "package.module:ClassName", or
                                     #   { policy = name, <argument> = value }; agents left out get
                                     #   the environment's default (the paper's)
    num_cats = 2                     # how many others (num_cats / num_humans): the scenario's own, default 1
    size = 11                        # world arguments: size, max_cycles, and Sharing's start

A scenario is evaluated in its run's world changed by what it sets: a run's ``size``,
``max_cycles``, ``view`` and its environment's own arguments carry over unless the scenario sets
them, except the number of other agents, which is the scenario's (its partners are its own, all of
them). A scenario cannot set ``view`` (it changes the size of the observation a trained network
takes) or Sharing's ``inventory_encoding`` (it changes what the observation's values mean): both
are refused by name. Every error is a :class:`~empathy_zoo.experiment.values.SweepConfigError`
naming the file, the table and the key.
"""

from __future__ import annotations

import os
import unicodedata
from collections.abc import Collection, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from empathy_zoo.document_checks import DocumentChecker
from empathy_zoo.engine.arguments import argument_types
from empathy_zoo.environments import DEFAULT_ENVIRONMENT, ENGINES
from empathy_zoo.evaluation_file import TRAINED_WITH, check_scenario_definition, check_scenario_set
from empathy_zoo.experiment.model import EnvVariant
from empathy_zoo.experiment.records import RunResult
from empathy_zoo.experiment.sweep_file import variant_of_table
from empathy_zoo.experiment.values import PolicyTable, SweepConfigError, check_keys, check_value, read_toml, type_name
from empathy_zoo.limits import MAX_SCENARIOS, not_a_regular_file
from empathy_zoo.names import LABEL_REFUSED_CATEGORIES, check_path_name
from empathy_zoo.policies import entry_label, parse_entry_label, recorded_entry

__all__ = [
    "SCENARIO_DIR",
    "TRAINED_WITH",
    "TRAINED_WITH_REASON",
    "MAX_REASON",
    "OBSERVATION_ARGUMENTS",
    "SET_KEYS",
    "Scenario",
    "ScenarioSet",
    "shipped_sets",
    "default_set_name",
    "scenario_set_path",
    "load_scenario_set",
    "parse_scenario_set",
    "parse_entry_label",
    "trained_with",
]

SCENARIO_DIR = Path(__file__).resolve().parent
"""Where the shipped scenario sets (``<env>.toml``) live."""
MAX_REASON = 500
"""Most characters a scenario's ``reason`` may hold (one line of a table)."""
TRAINED_WITH_REASON = "The run's own partners and world, as its result file records them: what it trained with."
"""The ``reason`` of :data:`TRAINED_WITH`."""
OBSERVATION_ARGUMENTS: dict[str, str] = {
    "view": "it changes the size of the observation a trained network takes (view×view values)",
    "inventory_encoding": "it changes what the values of the observation mean to a trained network",
}
"""Environment arguments a scenario may not set, and why (the run's own are kept)."""
SET_KEYS: dict[str, Any] = {"env": str, "name": str, "description": str, "held_out": bool}
"""Keys of the ``[scenario_set]`` table and their types. ``held_out`` may only be ``true`` (or be
left out): every scenario set is a held-out set, played beside partners a run never trained with
(an evaluation marks a scenario that is the run's own world as not held out by itself), so a set
saying ``held_out = false`` asks for something the suite does not do and is refused."""
TOP_TABLES = ("scenario_set", "scenarios")


@dataclass(frozen=True)
class Scenario:
    """One scenario: a name, why it is there, and its environment variant."""

    name: str
    """Its name in evaluation files and tables (letters, digits, ``_``, ``-``, ``.``)."""
    reason: str
    """One line: what it tests, fixed before any result is seen."""
    variant: EnvVariant
    """The scenario as its file gives it, on the environment's defaults: its own arguments
    (:attr:`EnvVariant.kwargs`) and its fixed agents (``None``: the environment's defaults)."""

    @property
    def env(self) -> str:
        return self.variant.env

    def for_run(self, run_env_kwargs: Mapping[str, Any]) -> EnvVariant:
        """The scenario in the world of a run trained with ``run_env_kwargs``: the run's arguments
        but the number of other agents, updated with the scenario's own (see the module page);
        ``ValueError`` naming the scenario when they do not fit together (a ``size`` smaller than
        the run's ``view``)."""
        count = ENGINES[self.env].count_argument
        kwargs = {key: value for key, value in run_env_kwargs.items() if key != count} | dict(self.variant.kwargs)
        try:
            return EnvVariant(self.env, kwargs, self.variant.fixed, self.name)
        except ValueError as error:
            raise ValueError(f"scenario {self.name!r} in the run's world {dict(run_env_kwargs)}: {error}") from None

    def definition(self) -> dict[str, Any]:
        """What the scenario file says of it, as plain data: ``name``, ``reason``, ``env_kwargs``
        (its own arguments) and ``fixed`` (``{agent: label}`` of every fixed agent, defaults included)."""
        return {
            "name": self.name,
            "reason": self.reason,
            "env_kwargs": dict(self.variant.kwargs),
            "fixed": {agent: entry_label(entry) for agent, entry in self.variant.fixed_policies().items()},
        }


@dataclass(frozen=True)
class ScenarioSet:
    """The scenarios of one environment, read from one file."""

    name: str
    """Its name: the folder of its evaluation files (``evaluations/<name>/``)."""
    env: str
    """The environment of every scenario."""
    scenarios: tuple[Scenario, ...]
    """Its scenarios, in file order (:data:`TRAINED_WITH` is not among them: it is every run's own)."""
    description: str = ""
    """One line on what the set is for."""
    source: str = "<scenarios>"
    """Where it was read from (in messages)."""

    def definition(self) -> dict[str, Any]:
        """The set as plain data (what an evaluation file records, and compares on a resume)."""
        return {
            "name": self.name,
            "env": self.env,
            "description": self.description,
            "scenarios": [scenario.definition() for scenario in self.scenarios],
        }


# ---------------------------------------------------------------------------- shipped sets
def shipped_sets() -> list[str]:
    """Names of the scenario sets shipped in :data:`SCENARIO_DIR` (one per environment)."""
    return sorted(p.stem for p in SCENARIO_DIR.glob("*.toml"))


def default_set_name(env: str) -> str | None:
    """The shipped scenario set of environment ``env`` (named like it), or ``None`` when none ships."""
    return env if env in shipped_sets() else None


def scenario_set_path(name_or_path: str | Path) -> Path:
    """The file of a shipped set's name, or ``name_or_path`` itself when it is a ``.toml`` file;
    anything else raises :class:`SweepConfigError` listing the shipped names."""
    text = str(name_or_path)
    if not text.strip():
        shipped = ", ".join(shipped_sets())
        raise SweepConfigError(f"a scenario set is a shipped name ({shipped}) or a .toml file, got an empty name")
    if text in shipped_sets():
        return SCENARIO_DIR / f"{text}.toml"
    path = Path(text)
    if path.suffix == ".toml" or os.path.lexists(path):
        problem = not_a_regular_file(path)
        if problem:
            raise SweepConfigError(f"scenario file {path} {problem}")
        return path
    raise SweepConfigError(
        f"unknown scenario set {text!r}; shipped: {', '.join(shipped_sets())} (or give a path to a .toml file)"
    )


def load_scenario_set(name_or_path: str | Path) -> ScenarioSet:
    """The scenario set of a shipped name (``coexistence_v0``) or of a TOML file (see the module page)."""
    path = scenario_set_path(name_or_path)
    return parse_scenario_set(read_toml(path), source=str(path), default_name=path.stem)


# ---------------------------------------------------------------------------- parsing
def parse_scenario_set(data: Mapping[str, Any], source: str = "<scenarios>", default_name: str | None = None) -> ScenarioSet:
    """The scenario set of the parsed TOML ``data``; ``source`` names the file in errors."""
    check_keys(data, TOP_TABLES, f"{source}: top level")
    header = data.get("scenario_set")
    if not isinstance(header, dict):
        raise SweepConfigError(
            f'{source}: declare a [scenario_set] table with env = "{DEFAULT_ENVIRONMENT}" (or another environment)'
        )
    where = f"{source}: [scenario_set]"
    check_keys(header, SET_KEYS, where)
    values = {key: check_value(value, SET_KEYS[key], f"{where} {key}") for key, value in header.items()}
    if "env" not in values:
        raise SweepConfigError(f"{where}: missing key 'env' (the environment of its scenarios; registered: {sorted(ENGINES)})")
    env = values["env"]
    if env not in ENGINES:
        raise SweepConfigError(f"{where} env: unknown environment {env!r}; registered: {sorted(ENGINES)}")
    name = values.get("name", default_name)
    if name is None:
        raise SweepConfigError(f"{where}: missing key 'name' (the set's name: the folder of its evaluation files)")
    try:
        check_path_name(name, "scenario set name")
    except ValueError as error:
        raise SweepConfigError(f"{where} name: {error}") from None
    if values.get("held_out", True) is not True:
        raise SweepConfigError(
            f"{where} held_out: a scenario set is always held out (its scenarios are played beside partners "
            "the run never trained with; one that is the run's own world is marked not held out by itself): "
            "write held_out = true or leave the key out, got false"
        )
    description = values.get("description", "")
    if _unprintable(description) is not None:
        raise SweepConfigError(
            f"{where} description: expected one line of printable text, got {description[:80]!r} "
            f"(it holds {_unprintable(description)})"
        )
    tables = data.get("scenarios")
    if not isinstance(tables, dict) or not tables:
        raise SweepConfigError(f"{source}: declare at least one [scenarios.<name>] table (reason = ..., fixed = ...)")
    if len(tables) > MAX_SCENARIOS:
        raise SweepConfigError(
            f"{source}: {len(tables):,} [scenarios.*] tables; a scenario set holds at most {MAX_SCENARIOS:,} "
            "(each is played for every run evaluated; docs/limits.md)"
        )
    scenarios = tuple(_scenario(key, table, env, source) for key, table in tables.items())
    scenario_set = ScenarioSet(name, env, scenarios, description, source)
    _check_as_recorded(scenario_set)
    return scenario_set


def _check_as_recorded(scenario_set: ScenarioSet) -> None:
    """The set as an evaluation file records it (:meth:`ScenarioSet.definition`) passes the checks the
    suite reads that file with (:func:`~empathy_zoo.evaluation_file.check_scenario_set`,
    :func:`~empathy_zoo.evaluation_file.check_scenario_definition`): every text field one line of
    printable text, every policy label one the reader parses. A set is refused when it is loaded,
    never after its agents are played, in a file nothing reads back."""
    check = DocumentChecker(
        Path(scenario_set.source),
        SweepConfigError,
        "a scenario file",
        "a scenario set an evaluation file can record",
        "fix the field in the scenario file",
    )
    definition = scenario_set.definition()
    check_scenario_set(check, definition, "[scenario_set]")
    for scenario in definition["scenarios"]:
        check_scenario_definition(check, scenario_set.env, scenario, f"[scenarios.{scenario['name']}]")


def _scenario(key: str, table: Any, env: str, source: str) -> Scenario:
    where = f"{source}: [scenarios.{key}]"
    if not isinstance(table, dict):
        raise SweepConfigError(f"{where}: must be a table (reason = ..., fixed = ...), got {type_name(table)}")
    try:
        check_path_name(key, "scenario name")
    except ValueError as error:
        raise SweepConfigError(f"{where}: {error}") from None
    if key == TRAINED_WITH:
        raise SweepConfigError(
            f"{where}: {TRAINED_WITH!r} is the name of every run's own partners; give the scenario another name"
        )
    engine = ENGINES[env]
    arguments = {name: kind for name, kind in argument_types(engine).items() if name not in OBSERVATION_ARGUMENTS}
    for name, why in OBSERVATION_ARGUMENTS.items():
        if name in table:
            raise SweepConfigError(f"{where} {name}: a scenario cannot set {name}: {why} (the run's own {name} is kept)")
    allowed = {"reason": str, "fixed": PolicyTable, **arguments}
    check_keys(table, allowed, where)
    checked = {name: check_value(value, allowed[name], f"{where} {name}") for name, value in table.items()}
    reason = checked.get("reason")
    if reason is None or not reason.strip() or _unprintable(reason) is not None or len(reason) > MAX_REASON:
        raise SweepConfigError(
            f"{where} reason: every scenario needs a one-line reason (what it tests) of printable text, at most "
            f"{MAX_REASON} characters, got {reason if reason is None else reason[:80]!r}"
            + ("" if reason is None or _unprintable(reason) is None else f" (it holds {_unprintable(reason)})")
        )
    kwargs = {name: value for name, value in checked.items() if name in arguments}
    return Scenario(key, reason.strip(), variant_of_table(env, kwargs, checked.get("fixed"), key, where))


def _unprintable(text: str) -> str | None:
    """The first character of ``text`` a one-line text may not hold (a control or format character,
    a line break: :data:`~empathy_zoo.names.LABEL_REFUSED_CATEGORIES`), named, or ``None``."""
    for character in text:
        category = unicodedata.category(character)
        if category in LABEL_REFUSED_CATEGORIES:
            return f"{unicodedata.name(character, f'U+{ord(character):04X}')} ({category})"
    return None


# ---------------------------------------------------------------------------- a run's own partners
def trained_with(result: RunResult, allowed_imports: Collection[str] = ()) -> Scenario:
    """The scenario of a run's own partners and world (:data:`TRAINED_WITH`): its environment, its
    ``config.env_kwargs`` and its fixed agents (``config.fixed``), from its result file as
    :func:`empathy_zoo.experiment.result_reader.read_result` gives it; ``ValueError`` naming the run when they
    do not make an environment variant. A recorded policy resolves only to a registered one or a
    name in ``allowed_imports`` (:func:`~empathy_zoo.policies.recorded_entry`): nothing a result
    file names is imported unless the user allowed it."""
    config = result.config
    try:
        fixed = {agent: recorded_entry(label, f"config.fixed.{agent}", allowed_imports) for agent, label in config.fixed.items()}
        variant = EnvVariant(result.env, dict(config.env_kwargs), fixed, TRAINED_WITH)
    except ValueError as error:
        raise ValueError(f"run {result.run_id}: its own partners do not make a scenario: {error}") from None
    return Scenario(TRAINED_WITH, TRAINED_WITH_REASON, variant)
