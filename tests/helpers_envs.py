"""The whole state of an environment face, to check that a rejected call changed nothing."""

from __future__ import annotations

import copy
from typing import Any

import numpy as np

from empathy_zoo.vector import VectorEnv

_AEC_FIELDS = (
    "agents",
    "agent_selection",
    "_actions",
    "terminations",
    "truncations",
    "rewards",
    "_cumulative_rewards",
    "infos",
    "_observations",
)


def env_state(env: Any) -> Any:
    """A deep copy of everything that decides what ``env`` (any face, wrappers included) does next."""
    if isinstance(env, VectorEnv):
        return copy.deepcopy(env.state())
    layers = []
    while True:
        fields = {
            key: value
            for key, value in vars(env).items()
            if key in _AEC_FIELDS or key in ("agents", "_step", "_last", "policies", "_painted", "_running", "_np_random")
        }
        layers.append((type(env).__name__, copy.deepcopy(fields)))
        if hasattr(env, "engine"):
            layers.append(("engine", env.engine.state()))
            return layers
        env = env.env if hasattr(env, "env") else env._env


def same(a: Any, b: Any) -> bool:
    """Deep equality over dicts, lists, numpy arrays, generators and plain objects."""
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        return isinstance(a, np.ndarray) and isinstance(b, np.ndarray) and a.dtype == b.dtype and np.array_equal(a, b)
    if isinstance(a, dict):
        return isinstance(b, dict) and a.keys() == b.keys() and all(same(a[k], b[k]) for k in a)
    if isinstance(a, (list, tuple)):
        return type(a) is type(b) and len(a) == len(b) and all(same(x, y) for x, y in zip(a, b, strict=True))
    if isinstance(a, np.random.Generator):
        return isinstance(b, np.random.Generator) and same(a.bit_generator.state, b.bit_generator.state)
    if hasattr(a, "__dict__") and not isinstance(a, type):
        return type(a) is type(b) and same(vars(a), vars(b))
    return a == b or (a != a and b != b)  # NaN equals NaN here
