"""The five actions every agent has, and their one validation for every face (PettingZoo parallel
and AEC, FixedAgents, the vector env, the Gymnasium adapter, fixed policies inside the training
path): an action is an integer in ``[0, 5)`` (a Python ``int``, a numpy integer, or a 0-d integer
array), never a float, a bool or anything truncated; anything else raises ``ValueError`` naming
the agent."""

from __future__ import annotations

from collections.abc import Collection, Mapping, Sequence
from enum import IntEnum
from typing import Any

import numpy as np

__all__ = ["Action", "NUM_ACTIONS", "check_action", "check_joint_action", "check_action_array"]


class Action(IntEnum):
    """The five actions every agent has (``Discrete(5)``); :data:`empathy_zoo.grid.MOVES` gives
    each one's displacement."""

    UP = 0
    """row - 1"""
    DOWN = 1
    """row + 1"""
    LEFT = 2
    """col - 1"""
    RIGHT = 3
    """col + 1"""
    STAY = 4
    """no-op"""


NUM_ACTIONS = len(Action)
"""How many actions every agent has (5)."""


def check_action(agent: str, action: Any, num_actions: int = NUM_ACTIONS) -> int:
    """``action`` as an ``int`` if it is a valid action of ``agent``, else ``ValueError``."""
    if type(action) is int or isinstance(action, np.integer):
        value = int(action)
    else:
        array = np.asarray(action) if isinstance(action, np.ndarray) else None
        if array is None or array.shape != () or array.dtype.kind not in "iu":
            raise ValueError(f"action for {agent} must be an integer in [0, {num_actions}), got {action!r}")
        value = int(array)
    if not 0 <= value < num_actions:
        raise ValueError(f"action {value} for {agent} is outside Discrete({num_actions})")
    return value


def check_joint_action(
    actions: Any, live: Sequence[str], known: Collection[str], num_actions: int = NUM_ACTIONS
) -> dict[str, int]:
    """``{agent: int}`` if ``actions`` maps exactly the ``live`` agents to valid actions; else
    ``ValueError`` naming the agent (``known``: every agent the environment has)."""
    if not isinstance(actions, Mapping):
        raise ValueError(f"actions must be a dict {{agent: action}} over {list(live)}, got {type(actions).__name__} {actions!r}")
    checked = {}
    for agent, action in actions.items():
        if agent not in live:
            if agent in known:
                raise ValueError(f"action given for {agent!r}, which is no longer in the environment")
            raise ValueError(f"action given for unknown agent {agent!r}; agents are {list(live)}")
        checked[agent] = action if type(action) is int and 0 <= action < num_actions else check_action(agent, action, num_actions)
    if len(checked) != len(live):
        missing = [agent for agent in live if agent not in checked]
        raise ValueError(f"no action given for live agent(s) {missing}")
    return checked


def check_action_array(
    actions: Any, shape: tuple[int, ...], agents: Sequence[str], present: np.ndarray | None = None, num_actions: int = NUM_ACTIONS
) -> np.ndarray:
    """``actions`` as an int64 array of ``shape`` (environments × agents, columns named by
    ``agents``) if every action (where ``present``, default everywhere) is valid, else ``ValueError``."""
    array = np.asarray(actions)
    if array.shape != shape:
        raise ValueError(f"actions must have shape {shape}, got {array.shape}")
    if array.dtype.kind not in "iu":
        raise ValueError(f"actions must be integers in [0, {num_actions}), got dtype {array.dtype}")
    bad = (array < 0) | (array >= num_actions)
    if present is not None:
        bad &= present
    if bad.any():
        env, column = np.argwhere(bad)[0]
        raise ValueError(
            f"invalid action {array[env, column].item()!r} for {agents[column]} in env {env}: "
            f"actions are integers in [0, {num_actions})"
        )
    return array.astype(np.int64, copy=False)
