"""The vector face of the engines: ``N`` environments as arrays, with autoreset.

``VectorEnv("coexistence_v0", num_envs=64, fixed={"cat_0": "random_walk"})`` steps 64
Coexistence environments at once; the learning agents (those not in ``fixed``) act through an
``(N, L)`` action array, the fixed ones act inside with their batched policies. Environment
``i`` is seeded with ``seeds[i]`` (or ``seed + i`` for an int), exactly as
``parallel_env().reset(seed=seeds[i])`` would be, and its fixed agents are seeded exactly as
:class:`empathy_zoo.FixedAgents` seeds them: the same seeds and actions give the same
trajectories on both faces. An environment whose episode ends is reset in the same step; its
last observation stays available in :attr:`VectorStep.final_observations`. Keyword arguments
beyond ``size``, ``view`` and ``max_cycles`` are the environment's own (e.g. Sharing's ``start``
and ``inventory_encoding``), exactly as the PettingZoo env takes them.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from empathy_zoo.actions import check_action_array
from empathy_zoo.engine import ENGINES, GridEngine
from empathy_zoo.engine.base import check_env_arguments
from empathy_zoo.fixed_agents import policy_seed
from empathy_zoo.metrics import METRIC_NAMES
from empathy_zoo.policies import BatchedPolicy, FixedPolicy, batched, make_policy
from empathy_zoo.randomness import check_seed

__all__ = ["VectorEnv", "VectorStep"]


@dataclass
class VectorStep:
    """One step of every environment, as arrays."""

    observations: np.ndarray
    """(N, L, V) float32: observations to act on next (after any autoreset)."""
    final_observations: np.ndarray
    """(N, L, V) float32: observations at the end of this step, before any autoreset."""
    swapped: np.ndarray
    """(N, L, V) float32: each learner's swapped observation with its closest other agent at the
    end of this step (before autoreset); zeros where :attr:`swapped_valid` is False."""
    swapped_valid: np.ndarray
    """(N, L) bool: that other agent is still present (and in view, with ``in_view_only``)."""
    swapped_other_terminated: np.ndarray
    """(N, L) bool: that other agent's episode ended for good this step (a harmed cat; the human
    when the last battery is taken). A time-limit truncation is not termination."""
    rewards: np.ndarray
    """(N, A) float32: the environment's rewards of all agents."""
    terminated: np.ndarray
    """(N, A) bool."""
    truncated: np.ndarray
    """(N, A) bool."""
    episode_over: np.ndarray
    """(N,) bool: the episode ended this step (the environment has been reset)."""
    harmed_by: np.ndarray
    """(N, A) int64: index of the agent that harmed each agent this step, else -1."""
    collected: np.ndarray
    """(N, A) bool: the agent collected a battery this step."""
    battery_return: np.ndarray
    """(N, A) float64: each agent's battery reward so far in the episode, this step included
    (taken before any autoreset)."""
    finished: dict[str, np.ndarray]
    """Metrics of the episodes that ended this step (SPEC §5, for the first learner), with
    ``"env"`` giving each one's environment index."""


class VectorEnv:
    """``num_envs`` environments of one kind stepped as arrays (see the module documentation)."""

    def __init__(
        self,
        env: str | type[GridEngine],
        num_envs: int,
        *,
        fixed: Mapping[str, FixedPolicy | str] | None = None,
        in_view_only: bool = False,
        size: int = 7,
        view: int = 5,
        max_cycles: int = 500,
        **env_options: Any,
    ) -> None:
        if isinstance(env, str):
            if env not in ENGINES:
                raise ValueError(f"unknown environment {env!r}; registered: {sorted(ENGINES)}")
            env = ENGINES[env]
        check_env_arguments(env, env_options)
        self.engine: GridEngine = env(num_envs, size=size, view=view, max_cycles=max_cycles, **env_options)
        self.num_envs = self.engine.num_envs
        self.agents = list(self.engine.agents)
        fixed = dict(fixed or {})
        unknown = [agent for agent in fixed if agent not in self.agents]
        if unknown:
            raise ValueError(f"fixed policies given for unknown agent(s) {unknown}; agents are {self.agents}")
        self.learners = [agent for agent in self.agents if agent not in fixed]
        if not self.learners:
            raise ValueError("every agent is fixed; leave at least one agent to learn")
        self.learner_index = [self.agents.index(agent) for agent in self.learners]
        self.fixed: dict[int, BatchedPolicy] = {
            self.agents.index(agent): batched(make_policy(policy), self.num_envs, agent) for agent, policy in fixed.items()
        }
        self.in_view_only = bool(in_view_only)
        self.obs_size = self.engine.obs_size
        self._observations: np.ndarray | None = None

    # ------------------------------------------------------------------ episode
    def reset(self, seed: int | Sequence[int] | None = None) -> np.ndarray:
        """Reset every environment; returns ``(N, L, V)`` observations."""
        if seed is None:
            seeds: list[int | None] = [None] * self.num_envs
        elif isinstance(seed, (int, np.integer)) and not isinstance(seed, bool):
            seeds = [int(check_seed(seed)) + i for i in range(self.num_envs)]
        else:
            if isinstance(seed, (str, bytes, bool)) or not hasattr(seed, "__len__"):
                raise ValueError(f"seed must be a non-negative int or a list of them, got {seed!r}")
            seeds = [check_seed(s) for s in seed]
            if len(seeds) != self.num_envs:
                raise ValueError(f"got {len(seeds)} seeds for {self.num_envs} environments")
        ids = np.arange(self.num_envs)
        self.engine.reset(ids, seeds)
        for index, policy in self.fixed.items():
            policy.reset(ids, [None if s is None else policy_seed(s, index) for s in seeds])
        self._observations = self._observe_learners()
        return self._observations

    def step(self, actions: np.ndarray) -> VectorStep:
        """Step with ``(N, L)`` learner actions; ends and resets finished episodes."""
        if self._observations is None:
            raise RuntimeError("call reset() before step()")
        actions = np.asarray(actions)
        if actions.ndim == 1 and len(self.learners) == 1:
            actions = actions[:, None]
        engine = self.engine
        # checked before the fixed agents act, so a bad action changes nothing
        actions = check_action_array(actions, (self.num_envs, len(self.learners)), self.learners,
                                     engine.present[:, self.learner_index])
        full = np.full((self.num_envs, engine.num_agents), 4, dtype=np.int64)
        full[:, self.learner_index] = actions
        for index, policy in self.fixed.items():
            observations = engine.observe(index) if policy.needs_observation else None
            full[:, index] = policy.act(observations, engine.t, engine.present[:, index])
        events = engine.step(full)
        battery_return = engine.episode_battery_return.copy()
        final = self._observe_learners()
        swapped, valid, other = self._swapped_closest()
        other_terminated = np.take_along_axis(events.terminated, other, axis=1)
        over = events.episode_over
        done_ids = np.flatnonzero(over)
        finished: dict[str, np.ndarray] = {"env": done_ids}
        if done_ids.size:
            metrics = engine.episode_metrics(done_ids, self.learner_index[0])
            finished.update({name: metrics[name] for name in (*METRIC_NAMES, "length")})
            engine.reset(done_ids)
            for index, policy in self.fixed.items():
                policy.reset(done_ids, [None] * done_ids.size)
            observations = final.copy()
            observations[done_ids] = self._observe_learners(done_ids)
        else:
            observations = final
        self._observations = observations
        return VectorStep(
            observations=observations, final_observations=final, swapped=swapped, swapped_valid=valid,
            swapped_other_terminated=other_terminated,
            rewards=events.rewards, terminated=events.terminated, truncated=events.truncated,
            episode_over=over, harmed_by=events.harmed_by, collected=events.collected,
            battery_return=battery_return, finished=finished,
        )

    # ------------------------------------------------------------------ observations
    def _observe_learners(self, env_ids: np.ndarray | None = None) -> np.ndarray:
        """``(n, L, V)`` observations of the learners (in ``env_ids``, default all)."""
        return _by_learner([self.engine.observe(viewer, env_ids) for viewer in self.learner_index])

    def _swapped_closest(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Each learner's swapped observation with its closest other agent, ``(N, L, V)``; where
        that agent exists, ``(N, L)``; and its index, ``(N, L)``."""
        engine = self.engine
        swapped, valid, others = [], [], []
        for viewer in self.learner_index:
            other, exists = engine.closest_other(viewer)
            others.append(other)
            if self.in_view_only:
                exists &= engine.in_view(viewer, other)
            picture = engine.observe_swapped(viewer, other)
            picture[~exists] = 0.0
            swapped.append(picture)
            valid.append(exists)
        return _by_learner(swapped), np.stack(valid, axis=1), np.stack(others, axis=1)

    def swapped_observations(self, viewer: str) -> tuple[np.ndarray, np.ndarray]:
        """``(N, A, V)`` swapped observations of ``viewer`` with every agent, and an ``(N, A)``
        mask of those that exist (other agent present, in view with ``in_view_only``; never self)."""
        v = self.agents.index(viewer)
        engine = self.engine
        out = np.zeros((self.num_envs, engine.num_agents, self.obs_size), dtype=np.float32)
        mask = np.zeros((self.num_envs, engine.num_agents), dtype=bool)
        for o in range(engine.num_agents):
            if o == v:
                continue
            ok = engine.present[:, o].copy()
            if self.in_view_only:
                ok &= engine.in_view(v, o)
            out[:, o] = np.where(ok[:, None], engine.observe_swapped(v, o), np.float32(0))
            mask[:, o] = ok
        return out, mask

    # ------------------------------------------------------------------ checkpoint
    def state(self) -> dict[str, Any]:
        """Everything needed to continue exactly (for checkpoints): the engine, the numeric state
        of the batched fixed policies, and the observations to act on."""
        policies = {
            str(index): {key: value for key, value in vars(policy).items() if isinstance(value, (np.ndarray, int, float))}
            for index, policy in self.fixed.items()
        }
        observations = None if self._observations is None else self._observations.copy()
        return {"engine": self.engine.state(), "policies": policies, "observations": observations}

    def load_state(self, state: Mapping[str, Any]) -> None:
        """Continue from :meth:`state`."""
        self.engine.load_state(state["engine"])
        for index, values in state["policies"].items():
            policy = self.fixed[int(index)]
            for key, value in values.items():
                current = getattr(policy, key)
                if isinstance(current, np.ndarray):
                    current[...] = value
                else:
                    setattr(policy, key, value)
        if state["observations"] is not None:
            self._observations = np.array(state["observations"], dtype=np.float32)


def _by_learner(columns: list[np.ndarray]) -> np.ndarray:
    """Stack per-learner ``(n, V)`` arrays to ``(n, L, V)`` (without a copy for one learner)."""
    return columns[0][:, None, :] if len(columns) == 1 else np.stack(columns, axis=1)
