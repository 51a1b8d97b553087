"""empathy-zoo: PettingZoo gridworlds for negative side effects, with Empathic DQN and baselines.

Environments: :mod:`empathy_zoo.coexistence_v0`, :mod:`empathy_zoo.sharing_v0` (PettingZoo
ParallelEnv and AEC), :class:`empathy_zoo.vector.VectorEnv` (many at once, as arrays).
"""

from __future__ import annotations

from empathy_zoo import coexistence_v0, sharing_v0
from empathy_zoo._version import __version__
from empathy_zoo.empathy import EmpathyWrapper
from empathy_zoo.environments import ENVIRONMENT_TABLE, face_module
from empathy_zoo.fixed_agents import FixedAgents
from empathy_zoo.policies import POLICIES, Patrol, RandomWalk, make_policy

ENVIRONMENTS = {name: face_module(name) for name in ENVIRONMENT_TABLE}
"""The PettingZoo face module of every environment, by name (the table: :mod:`empathy_zoo.environments`)."""

__all__ = [
    "coexistence_v0",
    "sharing_v0",
    "ENVIRONMENTS",
    "EmpathyWrapper",
    "FixedAgents",
    "POLICIES",
    "Patrol",
    "RandomWalk",
    "make_policy",
    "__version__",
]
