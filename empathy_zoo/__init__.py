"""empathy-zoo: PettingZoo gridworlds for negative side effects, with Empathic DQN and baselines.

Environments: :mod:`empathy_zoo.coexistence_v0`, :mod:`empathy_zoo.sharing_v0`,
:mod:`empathy_zoo.charger_v0`, :mod:`empathy_zoo.vase_v0`, :mod:`empathy_zoo.helping_v0` (PettingZoo
ParallelEnv and AEC),
:class:`empathy_zoo.vector.VectorEnv` (many at once, as arrays).
"""

from __future__ import annotations

from collections.abc import Mapping
from types import ModuleType
from typing import TYPE_CHECKING

from empathy_zoo import charger_v0, coexistence_v0, helping_v0, sharing_v0, vase_v0
from empathy_zoo._version import __version__
from empathy_zoo.empathy import EmpathyWrapper
from empathy_zoo.environments import FACES
from empathy_zoo.fixed_agents import FixedAgents
from empathy_zoo.policies import POLICIES, Patrol, RandomWalk, make_policy

if TYPE_CHECKING:  # (imported on first use: see __getattr__)
    from empathy_zoo.agent_file import load_agent
    from empathy_zoo.trained_agent import TrainedAgent

ENVIRONMENTS: Mapping[str, ModuleType] = FACES
"""The PettingZoo face module of every environment, by name (the table: :mod:`empathy_zoo.environments`)."""

__all__ = [
    "coexistence_v0",
    "sharing_v0",
    "charger_v0",
    "vase_v0",
    "helping_v0",
    "ENVIRONMENTS",
    "EmpathyWrapper",
    "FixedAgents",
    "POLICIES",
    "Patrol",
    "RandomWalk",
    "make_policy",
    "load_agent",
    "TrainedAgent",
    "__version__",
]

_LAZY = {"load_agent": "empathy_zoo.agent_file", "TrainedAgent": "empathy_zoo.trained_agent"}
"""Names imported on first use (they import torch, which ``import empathy_zoo`` does not)."""


def __getattr__(name: str) -> object:
    if name in _LAZY:
        import importlib

        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module 'empathy_zoo' has no attribute {name!r}")
