"""``FixedAgents``: a ParallelEnv whose agents are only the learners; fixed agents act inside."""

from __future__ import annotations

import contextlib
import copy
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np
from gymnasium.utils import EzPickle
from pettingzoo import ParallelEnv
from pettingzoo.utils.wrappers import BaseParallelWrapper

from empathy_zoo.actions import check_joint_action
from empathy_zoo.engine.base import GridEngine
from empathy_zoo.policies import (
    FixedPolicy,
    PolicyEntry,
    checked_policy_action,
    make_policy,
    policy_context,
    unsaved_policy,
)
from empathy_zoo.randomness import STREAMS, derive_key

__all__ = ["FixedAgents", "policy_seed", "undo_point"]


def policy_seed(env_seed: int, agent_index: int) -> int:
    """The seed a fixed agent gets when its environment is reset with ``env_seed``."""
    return derive_key(env_seed, STREAMS["fixed_agent"] + agent_index)


def undo_point(policy: Any) -> Callable[[], None]:
    """A function that puts ``policy`` (per-environment or batched) back as it is now: a copy of
    its own ``state()``, given back with ``load_state``; nothing for one that declares
    ``stateless = True``; a deep copy of its attributes for one that saves no state (or, copied
    per environment, a state that is no plain data). A step
    takes one of every fixed policy before any acts, so a step refused because one chose an
    invalid action leaves every policy's stream where it was."""
    if getattr(policy, "stateless", False) is True:
        return lambda: None
    if unsaved_policy(policy) is None:
        try:
            saved = policy.state()
        except ValueError:  # (the per-environment copies refuse a state that is no plain data: copied below)
            pass
        else:
            with contextlib.suppress(Exception):  # a state that cannot be copied is given back as it was taken
                saved = copy.deepcopy(saved)  # (a state may share its arrays with the policy)
            return lambda: policy.load_state(saved)
    try:
        attributes = copy.deepcopy(vars(policy))
    except Exception:  # no attributes to copy (slots), or ones that cannot be copied
        return lambda: None

    def restore() -> None:
        vars(policy).clear()
        vars(policy).update(attributes)

    return restore


class FixedAgents(BaseParallelWrapper, EzPickle):
    """Drive the agents named in ``policies`` inside the environment.

    ``FixedAgents(env, {"cat_0": RandomWalk()})`` (or ``{"cat_0": "random_walk"}``, or a policy
    entry ``{"cat_0": {"policy": "pkg.mod:Chaser", "speed": 2}}``) returns a ParallelEnv whose
    ``agents`` are the remaining (learning) agents; ``env`` is one of the suite's gridworlds.
    Each fixed agent is reset with a seed derived from the env's seed at ``reset(seed=...)``, so
    the same seed gives the same trajectory; ``reset()`` without a seed continues every stream. A
    fixed policy receives its own observation and its context (the env's ``infos`` entry,
    ``step``, ``agent``, ``size``, and ``positions`` if it declares ``needs_state``; see
    :class:`empathy_zoo.policies.FixedPolicy`), exactly as the vector env gives them.
    """

    def __init__(self, env: ParallelEnv, policies: Mapping[str, FixedPolicy | PolicyEntry]) -> None:
        BaseParallelWrapper.__init__(self, env)
        EzPickle.__init__(self, env, policies)
        engine = getattr(env.unwrapped, "engine", None)
        if not isinstance(engine, GridEngine):
            raise ValueError(
                f"FixedAgents drives the fixed agents of the suite's gridworlds (an env with an engine), "
                f"got {type(env.unwrapped).__name__}"
            )
        self._engine = engine
        all_agents = list(env.possible_agents)
        unknown = [agent for agent in policies if agent not in all_agents]
        if unknown:
            raise ValueError(f"fixed policies given for unknown agent(s) {unknown}; agents are {all_agents}")
        self.policies = {agent: make_policy(policy) for agent, policy in policies.items()}
        self.possible_agents = [agent for agent in all_agents if agent not in self.policies]
        if not self.possible_agents:
            raise ValueError("every agent is fixed; leave at least one agent to learn")
        self._fixed_index = {agent: all_agents.index(agent) for agent in self.policies}
        self._num_actions = int(env.action_space(all_agents[0]).n)
        self._last: dict[str, tuple[np.ndarray, dict]] = {}
        self.agents: list[str] = []

    def reset(self, seed: int | None = None, options: Mapping[str, Any] | None = None) -> tuple[dict, dict]:
        observations, infos = self.env.reset(seed=seed, options=options)  # (a bad seed or option changes nothing)
        for agent, policy in self.policies.items():
            policy.reset(None if seed is None else policy_seed(seed, self._fixed_index[agent]))
        self._remember(observations, infos)
        self.agents = [agent for agent in self.env.agents if agent not in self.policies]
        return self._learners(observations), self._learners(infos)

    def step(self, actions: Mapping[str, Any]) -> tuple[dict, dict, dict, dict, dict]:
        """Step with the learners' ``actions``; they are checked before any fixed agent acts, so
        a bad one raises ``ValueError`` and changes nothing. So does a fixed policy's invalid
        action: every fixed policy is put back as it was before the step (:func:`undo_point`)."""
        if isinstance(actions, Mapping):
            for agent in actions:
                if agent in self.policies:
                    raise ValueError(f"{agent} is a fixed agent driven inside FixedAgents; do not pass its action")
        if not self.env.agents:
            raise RuntimeError("step() called with no live agents; call reset() first")
        merged: dict[str, Any] = check_joint_action(actions, self.agents, self.possible_agents, self._num_actions)
        acting = [agent for agent in self.env.agents if agent in self.policies]
        undo = [undo_point(self.policies[agent]) for agent in acting]
        try:  # every fixed agent's action is chosen and checked before the environment moves
            for agent in acting:
                observation, info = self._last[agent]
                policy = self.policies[agent]
                context = policy_context(
                    self._engine, 0, self._fixed_index[agent], info, bool(getattr(policy, "needs_state", False))
                )
                merged[agent] = checked_policy_action(policy, agent, policy.act(observation, context), self._num_actions)
            observations, rewards, terminations, truncations, infos = self.env.step(merged)
        except BaseException:
            for restore in undo:  # (an earlier policy's stream has moved: put it back)
                restore()
            raise
        self._remember(observations, infos)
        self.agents = [agent for agent in self.env.agents if agent not in self.policies]
        learners = self._learners
        return learners(observations), learners(rewards), learners(terminations), learners(truncations), learners(infos)

    def _remember(self, observations: dict, infos: dict) -> None:
        for agent in self.policies:
            if agent in observations:
                self._last[agent] = (observations[agent], infos.get(agent, {}))

    def _learners(self, values: dict) -> dict:
        """A copy of ``values`` without the fixed agents."""
        kept = dict(values)
        for agent in self.policies:
            kept.pop(agent, None)
        return kept
