"""Every environment of the suite in one table: its engine, its PettingZoo face, the fixed agents
the paper gives it, and its Gymnasium id.

A new environment is an engine (``empathy_zoo/engine/<name>.py``: the rules, stepping N
environments as arrays), a face module (``empathy_zoo/<name>.py``: ``raw_env``, ``parallel_env``,
``env``; its docstring is the environment's documentation page) and one entry in
:data:`ENVIRONMENT_TABLE`. Everything else (the vector env, the runner, sweep files, the Gymnasium
face, the command line) looks environments up here.
"""

from __future__ import annotations

import importlib
from collections.abc import Mapping
from dataclasses import dataclass, field
from types import ModuleType
from typing import Any

from empathy_zoo.engine.base import GridEngine
from empathy_zoo.engine.coexistence import CoexistenceEngine
from empathy_zoo.engine.sharing import SharingEngine

__all__ = [
    "Environment",
    "ENVIRONMENT_TABLE",
    "ENGINES",
    "DEFAULT_POLICIES",
    "DEFAULT_ARGUMENTS",
    "GYM_IDS",
    "face_module",
    "default_policies",
]


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
    ),
    "sharing_v0": Environment(
        SharingEngine,
        "empathy_zoo.sharing_v0",
        "empathy_zoo/Sharing-v0",
        {"human_0": "patrol"},
        {"size": 7, "view": 5, "max_cycles": 500, "start": "random", "inventory_encoding": "count_plus_one", "num_humans": 1},
    ),
}
"""Every environment, by name."""

ENGINES: dict[str, type[GridEngine]] = {name: env.engine for name, env in ENVIRONMENT_TABLE.items()}
"""Engine class of every environment, by name."""
DEFAULT_POLICIES: dict[str, dict[str, str]] = {name: dict(env.fixed) for name, env in ENVIRONMENT_TABLE.items()}
"""The paper's fixed agents of every environment (a copy of the table's: changing it changes nothing)."""
DEFAULT_ARGUMENTS: dict[str, dict[str, Any]] = {name: dict(env.arguments) for name, env in ENVIRONMENT_TABLE.items()}
"""Every environment's arguments at their defaults (a copy of the table's: changing it changes nothing)."""


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


GYM_IDS: dict[str, str] = {env.gym_id: name for name, env in ENVIRONMENT_TABLE.items()}
"""Gymnasium id -> environment name."""


def face_module(name: str) -> ModuleType:
    """The PettingZoo face module of environment ``name`` (``ValueError`` for an unknown name)."""
    if name not in ENVIRONMENT_TABLE:
        raise ValueError(f"unknown environment {name!r}; registered: {sorted(ENVIRONMENT_TABLE)}")
    return importlib.import_module(ENVIRONMENT_TABLE[name].module)
