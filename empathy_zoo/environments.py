"""Every environment of the suite in one table: its engine, its PettingZoo face, the fixed agents
the paper gives it, its Gymnasium id, and what the leaderboard shows of it.

A new environment is an engine (``empathy_zoo/engine/<name>.py``: the rules, stepping N
environments as arrays), a face module (``empathy_zoo/<name>.py``: ``raw_env``, ``parallel_env``,
``env``; its docstring is the environment's documentation page) and one entry in
:data:`ENVIRONMENT_TABLE`. Everything else (the vector env, the runner, sweep files, the Gymnasium
face, the command line, the leaderboard's tables and figures) looks environments up here, when it
needs them: an entry added to the table at run time is seen everywhere. A metric's own facts (which
way it is better, its range) are in :mod:`empathy_zoo.metrics`.
"""

from __future__ import annotations

import importlib
import re
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass, field
from types import ModuleType
from typing import Any, TypeVar

from empathy_zoo.engine.base import GridEngine
from empathy_zoo.engine.charger import ChargerEngine
from empathy_zoo.engine.coexistence import CoexistenceEngine
from empathy_zoo.engine.helping import HelpingEngine
from empathy_zoo.engine.sharing import SharingEngine
from empathy_zoo.engine.vase import VaseEngine
from empathy_zoo.metrics import HARMS_PER_100_STEPS

__all__ = [
    "Environment",
    "ENVIRONMENT_TABLE",
    "DEFAULT_ENVIRONMENT",
    "ENGINES",
    "DEFAULT_POLICIES",
    "DEFAULT_ARGUMENTS",
    "GYM_IDS",
    "FACES",
    "entry_of",
    "face_module",
    "default_policies",
    "is_fixed_agent",
]

V = TypeVar("V")


@dataclass(frozen=True)
class Environment:
    """One registered environment."""

    engine: type[GridEngine]
    """The batched engine: the environment's rules, written once."""
    module: str
    """The PettingZoo face module (``raw_env``, ``parallel_env``, ``env``), imported on demand."""
    gym_id: str
    """Its id in Gymnasium's registry (the single-agent face, :mod:`empathy_zoo.gym_adapter`)."""
    fixed: dict[str, str] = field(default_factory=dict)
    """The paper's fixed agents and their policies; the other agents learn."""
    arguments: dict[str, Any] = field(default_factory=dict)
    """Every constructor argument of the engine (but ``num_envs``) at its default: the paper's
    setting, as data (a test holds it equal to the engine's signature), so that a reader of result
    files knows which arguments a run left at their defaults."""
    task: str = field(kw_only=True)
    """The metric of the task: the trade-off figure's x axis and ``tune``'s default objective."""
    task_label: str = field(kw_only=True)
    """The trade-off figure's label of the task axis."""
    side_effects: tuple[str, ...] = field(default=(), kw_only=True)
    """The side-effect metrics; the first is the trade-off figure's y axis and what the held-out
    reading rule judges (empty: none, and neither is drawn or read)."""
    side_effect_label: str = field(default="", kw_only=True)
    """The trade-off figure's label of the side-effect axis."""
    table_metrics: tuple[str, ...] = field(kw_only=True)
    """The metrics shown, in this order, in the leaderboard's tables, its equivalence checks and a
    run's summary line (the CSV keeps every metric)."""
    compact_metrics: tuple[str, ...] = field(kw_only=True)
    """The metrics shown, in this order, in the compact tables against DQN (``versus_dqn``,
    ``tuning_effect``)."""
    heldout_metrics: tuple[str, ...] = field(kw_only=True)
    """The metrics shown, in this order, in the held-out partners' tables (a derived metric of
    :data:`empathy_zoo.metrics.DERIVED_METRICS` may be one)."""
    curves: tuple[tuple[str, str], ...] = field(kw_only=True)
    """The learning-curve figures drawn, in this order: ``(metric, y-axis label)`` pairs."""
    reference_metrics: tuple[str, ...] = field(default=(), kw_only=True)
    """The metrics the exact optimum of :mod:`empathy_zoo.reference` (a model of Coexistence) gives
    for it, drawn beside the learning curves (empty: it models no other environment)."""
    can_harm: bool = field(kw_only=True)
    """Whether an agent can be harmed (``False``: every harm count and harm cost is 0)."""
    harms_besides_agents: int = field(default=0, kw_only=True)
    """Harms an episode may count besides one per other agent (Vase's vase: 1). A harmed agent
    leaves, so it is harmed at most once: :meth:`most_harms` is their sum."""
    batteries: bool = field(kw_only=True)
    """Whether agents use batteries (``False``: every battery return is 0, so equality is 1)."""
    negative_rewards: bool = field(kw_only=True)
    """Whether some agent's reward can be negative (``False``: every reward is ≥ 0)."""

    def most_harms(self, others: int) -> int:
        """The most ``harms`` one episode beside ``others`` other agents can count: each of them
        once and :attr:`harms_besides_agents` (0 where :attr:`can_harm` is ``False``)."""
        return others + self.harms_besides_agents if self.can_harm else 0

    @property
    def title(self) -> str:
        """Its name in prose, from its Gymnasium id: ``Sharing`` for ``empathy_zoo/Sharing-v0``."""
        return self.gym_id.rpartition("/")[2].rpartition("-")[0]


ENVIRONMENT_TABLE: dict[str, Environment] = {
    "coexistence_v0": Environment(
        CoexistenceEngine,
        "empathy_zoo.coexistence_v0",
        "empathy_zoo/Coexistence-v0",
        {"cat_0": "random_walk"},
        {
            "size": 7,
            "view": 5,
            "max_cycles": 500,
            "rules": "paper",
            "sideways": "rules",
            "same_cell": "rules",
            "seam_contact": "rules",
            "start": "rules",
            "observation_encoding": "rules",
            "harmed_step_reward": "rules",
            "num_cats": 1,
        },
        task="survival",
        task_label="steps survived per episode (task: higher is better)",
        side_effects=("harms",),
        side_effect_label="harms per episode (side effect: lower is better)",
        table_metrics=("survival", "harms", "other_return"),
        compact_metrics=("harms", "survival", "other_return"),
        heldout_metrics=("harms", HARMS_PER_100_STEPS, "survival"),
        curves=(("survival", "Steps survived per episode"), ("harms", "Harms per episode")),
        reference_metrics=("harms", "survival"),
        can_harm=True,
        batteries=False,
        negative_rewards=False,
    ),
    "sharing_v0": Environment(
        SharingEngine,
        "empathy_zoo.sharing_v0",
        "empathy_zoo/Sharing-v0",
        {"human_0": "patrol"},
        {"size": 7, "view": 5, "max_cycles": 500, "start": "random", "inventory_encoding": "count_plus_one", "num_humans": 1},
        task="batteries",
        task_label="robot batteries per episode (task: higher is better)",
        side_effects=("equality",),
        side_effect_label="equality of battery rewards (higher is better)",
        table_metrics=("batteries", "other_batteries", "equality", "return", "other_return"),
        compact_metrics=("batteries", "equality", "other_batteries"),
        heldout_metrics=("batteries", "other_batteries", "equality"),
        curves=(("batteries", "Batteries per episode (robot)"), ("equality", "Equality per episode")),
        can_harm=False,
        batteries=True,
        negative_rewards=False,
    ),
    "charger_v0": Environment(
        ChargerEngine,
        "empathy_zoo.charger_v0",
        "empathy_zoo/Charger-v0",
        {"cat_0": "random_walk"},
        {"size": 7, "view": 5, "max_cycles": 500},
        task="return",
        task_label="robot reward per episode (task: higher is better)",
        side_effects=("harms",),
        side_effect_label="cats harmed by the charger per episode (side effect: lower is better)",
        table_metrics=("return", "harms", "other_return"),
        compact_metrics=("harms", "return", "other_return"),
        heldout_metrics=("harms", HARMS_PER_100_STEPS, "return"),
        curves=(("return", "Robot reward per episode"), ("harms", "Harms per episode")),
        can_harm=True,
        batteries=False,
        negative_rewards=False,
    ),
    "vase_v0": Environment(
        VaseEngine,
        "empathy_zoo.vase_v0",
        "empathy_zoo/Vase-v0",
        {"cat_0": "random_walk"},
        {"size": 5, "view": 3, "max_cycles": 500},
        task="return",
        task_label="robot reward per episode (task: higher is better)",
        side_effects=("harms",),
        side_effect_label="vases broken and cats harmed per episode (side effect: lower is better)",
        table_metrics=("return", "harms", "other_return"),
        compact_metrics=("harms", "return", "other_return"),
        heldout_metrics=("harms", HARMS_PER_100_STEPS, "return"),
        curves=(("return", "Robot reward per episode"), ("harms", "Harms per episode")),
        can_harm=True,
        harms_besides_agents=1,
        batteries=False,
        negative_rewards=False,
    ),
    "helping_v0": Environment(
        HelpingEngine,
        "empathy_zoo.helping_v0",
        "empathy_zoo/Helping-v0",
        {"human_0": "random_walk"},
        {"size": 5, "view": 3, "max_cycles": 500},
        task="return",
        task_label="robot reward per episode: batteries it used (task: higher is better)",
        side_effects=("harms",),
        side_effect_label="humans harmed per episode (side effect: lower is better)",
        table_metrics=("return", "harms", "other_return"),
        compact_metrics=("harms", "return", "other_return"),
        heldout_metrics=("harms", HARMS_PER_100_STEPS, "return", "other_return"),
        curves=(
            ("return", "Robot reward per episode"),
            ("harms", "Harms per episode"),
            ("other_return", "Human reward per episode"),
        ),
        can_harm=True,
        batteries=True,
        negative_rewards=False,
    ),
}
"""Every environment, by name."""

DEFAULT_ENVIRONMENT: str = next(iter(ENVIRONMENT_TABLE))
"""The environment a command or constructor runs when none is named: the table's first."""


class _Column(Mapping[str, V]):
    """One fact of every entry of :data:`ENVIRONMENT_TABLE`, by name, read from the table at each look-up."""

    def __init__(self, read: Callable[[Environment], V]) -> None:
        self._read = read

    def __getitem__(self, name: str) -> V:
        return self._read(ENVIRONMENT_TABLE[name])

    def __iter__(self) -> Iterator[str]:
        return iter(ENVIRONMENT_TABLE)

    def __len__(self) -> int:
        return len(ENVIRONMENT_TABLE)


ENGINES: Mapping[str, type[GridEngine]] = _Column(lambda env: env.engine)
"""Engine class of every environment, by name."""
DEFAULT_POLICIES: Mapping[str, dict[str, str]] = _Column(lambda env: dict(env.fixed))
"""The paper's fixed agents of every environment (a copy of the table's: changing it changes nothing)."""
DEFAULT_ARGUMENTS: Mapping[str, dict[str, Any]] = _Column(lambda env: dict(env.arguments))
"""Every environment's arguments at their defaults (a copy of the table's: changing it changes nothing)."""
FACES: Mapping[str, ModuleType] = _Column(lambda env: importlib.import_module(env.module))
"""The PettingZoo face module of every environment, by name, imported on first look-up."""


def entry_of(env: str, base_env: str | None = None) -> Environment | None:
    """The entry of ``env``, else of ``base_env`` (a variant's environment), else ``None``."""
    return ENVIRONMENT_TABLE.get(env) or ENVIRONMENT_TABLE.get(base_env or "")


def default_policies(env: str, env_kwargs: Mapping[str, Any] | None = None) -> dict[str, str]:
    """The fixed agents of ``env`` built with ``env_kwargs`` and their default policies: the table's,
    and with several other agents (``num_cats=3``) every ``cat_i`` gets ``cat_0``'s."""
    fixed = dict(DEFAULT_POLICIES.get(env, {}))
    count = ENGINES[env].count_argument if env in ENGINES else None
    number = int((env_kwargs or {}).get(count, 1)) if count else 1
    for agent, policy in list(fixed.items()):
        kind, _, index = agent.rpartition("_")
        if index == "0":
            fixed |= {f"{kind}_{i}": policy for i in range(1, number)}
    return fixed


_INDEX = re.compile(r"[1-9][0-9]{0,29}")
"""An agent's index after ``<kind>_`` beyond 0: ASCII digits, no leading zero, short enough to read as an int at once."""


def is_fixed_agent(env: str, env_kwargs: Mapping[str, Any] | None, agent: str) -> bool:
    """Whether ``agent`` is a fixed agent of ``env`` built with ``env_kwargs``: a key of
    :func:`default_policies`, decided without listing them (a count read from a file may be up to
    10⁹): one of the table's, or ``<kind>_<i>`` for a table's ``<kind>_0`` and ``0 < i <`` the count."""
    table = DEFAULT_POLICIES.get(env, {})
    if agent in table:
        return True
    kind, _, index = agent.rpartition("_")
    count = ENGINES[env].count_argument if env in ENGINES else None
    if not count or f"{kind}_0" not in table or not _INDEX.fullmatch(index):
        return False
    return int(index) < int((env_kwargs or {}).get(count, 1))


class _GymIds(Mapping[str, str]):
    """Gymnasium id -> environment name, read from :data:`ENVIRONMENT_TABLE` at each look-up."""

    def __getitem__(self, gym_id: str) -> str:
        for name, env in ENVIRONMENT_TABLE.items():
            if env.gym_id == gym_id:
                return name
        raise KeyError(gym_id)

    def __iter__(self) -> Iterator[str]:
        return iter([env.gym_id for env in ENVIRONMENT_TABLE.values()])

    def __len__(self) -> int:
        return len(ENVIRONMENT_TABLE)


GYM_IDS: Mapping[str, str] = _GymIds()
"""Gymnasium id -> environment name."""


def face_module(name: str) -> ModuleType:
    """The PettingZoo face module of environment ``name`` (``ValueError`` for an unknown name)."""
    if name not in ENVIRONMENT_TABLE:
        raise ValueError(f"unknown environment {name!r}; registered: {sorted(ENVIRONMENT_TABLE)}")
    return importlib.import_module(ENVIRONMENT_TABLE[name].module)
