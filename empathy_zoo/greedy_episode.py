"""Greedy episodes of a trained agent in its own environment, scored as the suite scores them.

:func:`agent_env` builds the PettingZoo environment a trained agent's file describes (``env`` and
``env_kwargs`` of :meth:`~empathy_zoo.trained_agent.TrainedAgent.describe`) inside
:class:`~empathy_zoo.FixedAgents`, the other agents driven by the policies the run trained beside
(the environment's defaults, then the run's recorded ``fixed``, then the caller's). :func:`play_greedy`
plays one episode with the agent acting greedily for the learner (``robot_0``) and returns its
metrics: the engine's :meth:`~empathy_zoo.engine.base.GridEngine.episode_metrics`, what
``infos[agent]["episode"]`` holds at the episode's end (:data:`~empathy_zoo.metrics.METRIC_NAMES`).
"""

from __future__ import annotations

from collections.abc import Callable, Collection, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from empathy_zoo.environments import default_policies, face_module
from empathy_zoo.fixed_agents import FixedAgents, policy_seed
from empathy_zoo.metrics import METRIC_NAMES
from empathy_zoo.policies import PolicyEntry, recorded_entry

__all__ = ["EpisodeStep", "EpisodeOutcome", "watch_env", "agent_policies", "agent_env", "play_greedy", "format_metrics"]


@dataclass(frozen=True)
class EpisodeStep:
    """What :func:`play_greedy` hands its ``on_step`` after the reset and after every step."""

    step: int
    """Steps taken so far (0 right after the reset)."""
    action: int | None
    """The agent's action of this step (``None`` after the reset)."""
    metrics: dict[str, float]
    """The episode's metrics so far, by :data:`~empathy_zoo.metrics.METRIC_NAMES`."""
    over: bool
    """The episode has ended (every learner terminated or truncated)."""
    env: FixedAgents
    """The environment, in the state after this step (its engine: ``env.unwrapped.engine``)."""


@dataclass(frozen=True)
class EpisodeOutcome:
    """One played episode."""

    seed: int
    """The seed the environment was reset with."""
    steps: int
    """Steps played."""
    ended: bool
    """The episode ended by its own rules; ``False`` when it was cut at ``max_steps``."""
    metrics: dict[str, float]
    """Its metrics at the last step played, by :data:`~empathy_zoo.metrics.METRIC_NAMES`."""
    actions: list[int]
    """The agent's actions, in order."""


def watch_env(
    env: str,
    env_kwargs: Mapping[str, Any] | None = None,
    fixed: Mapping[str, PolicyEntry] | None = None,
    render_mode: str | None = None,
) -> FixedAgents:
    """The PettingZoo environment ``env`` built with ``env_kwargs``, its other agents driven by
    ``fixed`` over the environment's default policies (:func:`~empathy_zoo.environments.default_policies`),
    leaving the learner (its first agent, ``robot_0``) alone to act; a policy for the learner, or
    another agent left without one, raises ``ValueError``."""
    kwargs = dict(env_kwargs or {})
    policies = {**default_policies(env, kwargs), **dict(fixed or {})}
    try:
        raw = face_module(env).parallel_env(render_mode=render_mode, **kwargs)
    except TypeError as error:  # (an argument the environment does not take)
        raise ValueError(f"{env} with {kwargs}: {error}") from None
    learner = raw.possible_agents[0]
    if learner in policies:
        raise ValueError(f"{learner} is the trained agent's; fixed policies are for the other agents {raw.possible_agents[1:]}")
    wrapped = FixedAgents(raw, policies)
    if wrapped.possible_agents != [learner]:
        others = [agent for agent in wrapped.possible_agents if agent != learner]
        raise ValueError(f"the trained agent acts for {learner}; give {others} fixed policies (AGENT=POLICY)")
    return wrapped


def agent_policies(
    agent: Any, fixed: Mapping[str, PolicyEntry] | None = None, allowed_imports: Collection[str] = ()
) -> dict[str, PolicyEntry]:
    """The other agents' policies beside ``agent`` in its environment: the environment's defaults,
    then the ``fixed`` agents its run recorded (its ``describe()``: the result file's ``config.fixed``,
    labels such as ``"patrol(period=3)"``, read back as policy entries), then ``fixed``.

    A recorded policy is data from the agent's file: it resolves only to a registered policy or a
    name in ``allowed_imports`` (:func:`~empathy_zoo.policies.recorded_entry`); one that ``fixed``
    replaces is not read at all."""
    description = agent.describe()
    given = dict(fixed or {})
    where = f"{description.get('file') or 'the agent file'}: header.fixed"
    recorded = {
        agent_name: recorded_entry(entry, f"{where}.{agent_name}", allowed_imports)
        for agent_name, entry in dict(description.get("fixed") or {}).items()
        if agent_name not in given
    }
    return {**default_policies(description["env"], dict(description["env_kwargs"])), **recorded, **given}


def agent_env(
    agent: Any,
    fixed: Mapping[str, PolicyEntry] | None = None,
    render_mode: str | None = None,
    allowed_imports: Collection[str] = (),
) -> FixedAgents:
    """The environment ``agent`` was trained in (its ``describe()``: ``env``, ``env_kwargs`` and the
    ``fixed`` agents it recorded), ``fixed`` replacing some of those policies (:func:`agent_policies`,
    which resolves a recorded policy only to a registered one or one of ``allowed_imports``);
    an agent whose observation is not the environment's raises ``ValueError``."""
    description = agent.describe()
    recorded = dict(description.get("fixed") or {})
    try:
        policies = agent_policies(agent, fixed, allowed_imports)
        env = watch_env(description["env"], description["env_kwargs"], policies, render_mode)
    except ValueError as error:
        if not recorded:
            raise
        raise ValueError(f"{error} (the run trained beside {recorded}; replace one with AGENT=POLICY)") from None
    size = int(env.observation_space(env.possible_agents[0]).shape[0])
    if int(description["obs_size"]) != size:
        raise ValueError(
            f"the agent takes observations of {description['obs_size']} values, but {description['env']} "
            f"with {description['env_kwargs']} gives {size}"
        )
    return env


def _metrics(env: FixedAgents, learner: int) -> dict[str, float]:
    metrics = env.unwrapped.engine.episode_metrics(np.zeros(1, dtype=np.int64), learner)
    return {name: float(metrics[name][0]) for name in METRIC_NAMES}


def play_greedy(
    agent: Any,
    env: FixedAgents,
    seed: int,
    max_steps: int | None = None,
    on_step: Callable[[EpisodeStep], None] | None = None,
) -> EpisodeOutcome:
    """One episode of ``env`` (from :func:`watch_env`) reset with ``seed``, ``agent`` choosing the
    learner's action from its observation each step (``agent.act(observation)``), until the episode
    ends or ``max_steps`` steps were played; ``on_step`` is called after the reset and each step.
    The agent is reset with the seed a fixed agent in its place would get (:func:`~empathy_zoo.fixed_agents.policy_seed`)."""
    if max_steps is not None and (isinstance(max_steps, bool) or not isinstance(max_steps, int) or max_steps < 1):
        raise ValueError(f"max_steps must be a positive int or None, got {max_steps!r}")
    (learner,) = env.possible_agents
    index = env.unwrapped.engine.agents.index(learner)
    observations, _ = env.reset(seed=seed)
    agent.reset(policy_seed(seed, index))
    actions: list[int] = []
    if on_step is not None:
        on_step(EpisodeStep(0, None, _metrics(env, index), not env.agents, env))
    while env.agents and (max_steps is None or len(actions) < max_steps):
        action = int(agent.act(observations[learner]))
        observations, *_ = env.step({learner: action})
        actions.append(action)
        if on_step is not None:
            on_step(EpisodeStep(len(actions), action, _metrics(env, index), not env.agents, env))
    return EpisodeOutcome(seed, len(actions), not env.agents, _metrics(env, index), actions)


def format_metrics(metrics: Mapping[str, float]) -> str:
    """``survival 500, harms 0, …``: the metrics in :data:`~empathy_zoo.metrics.METRIC_NAMES` order, as ``play`` prints them."""
    return ", ".join(f"{name} {float(metrics[name]):g}" for name in METRIC_NAMES)
