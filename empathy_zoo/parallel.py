"""The PettingZoo ``ParallelEnv`` face of an engine with one environment."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any, ClassVar

import numpy as np
from gymnasium import spaces
from gymnasium.utils import EzPickle
from pettingzoo import ParallelEnv
from pettingzoo.utils.conversions import parallel_to_aec_wrapper
from pettingzoo.utils.env import AECEnv

from empathy_zoo.actions import NUM_ACTIONS, Action, check_action, check_joint_action
from empathy_zoo.engine.base import GridEngine, check_env_arguments
from empathy_zoo.engine.sight import swap_order
from empathy_zoo.metrics import METRIC_NAMES
from empathy_zoo.render import render_rgb, render_text

__all__ = ["GridParallelEnv", "GridAECEnv", "grid_metadata", "env_constructors"]

AgentID = str
STAY = int(Action.STAY)


class GridParallelEnv(ParallelEnv, EzPickle):
    """A ``ParallelEnv`` whose rules live in ``engine_class`` (stepping one environment)."""

    engine_class: ClassVar[type[GridEngine]]
    metadata: ClassVar[dict[str, Any]]

    def __init__(
        self,
        size: int | None = None,
        view: int | None = None,
        max_cycles: int | None = None,
        render_mode: str | None = None,
        **env_options: Any,
    ) -> None:
        """``size``, ``view`` and ``max_cycles`` left ``None`` are the engine's defaults.
        ``env_options``: the environment's own arguments (``engine_class.extra_arguments``, and
        its ``count_argument``: how many other agents); any other keyword raises
        :class:`~empathy_zoo.engine.arguments.UnknownArgumentError` (a ``ValueError`` and a
        ``TypeError``) naming it."""
        EzPickle.__init__(self, size=size, view=view, max_cycles=max_cycles, render_mode=render_mode, **env_options)
        check_env_arguments(self.engine_class, env_options)
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(f"render_mode must be one of {self.metadata['render_modes']} or None, got {render_mode!r}")
        self.render_mode = render_mode
        given = {"size": size, "view": view, "max_cycles": max_cycles}
        self.engine = self.engine_class(1, **{k: v for k, v in given.items() if v is not None}, **env_options)
        self.possible_agents: list[AgentID] = list(self.engine.agents)
        self.agents: list[AgentID] = []
        obs_space = spaces.Box(
            low=np.float32(self.engine.obs_low),
            high=np.float32(self.engine.obs_high),
            shape=(self.engine.obs_size,),
            dtype=np.float32,
        )
        self.observation_spaces = dict.fromkeys(self.possible_agents, obs_space)
        self.action_spaces = {agent: spaces.Discrete(NUM_ACTIONS) for agent in self.possible_agents}
        self._index = {agent: i for i, agent in enumerate(self.possible_agents)}
        # Every observation and every swapped observation of a step is painted at once, as the rows
        # of one batch of views: view k shows the agents in order _view_order[k] to _viewers.viewer[k]
        # (rows 0..A-1: each agent's own view; then one row per (viewer, other) swap).
        count = self.engine.num_agents
        pairs = [(v, o) for v in range(count) for o in range(count) if v != o]
        order = [list(range(count)) for _ in range(count)]
        order += [swap_order(count, v, o).tolist() for v, o in pairs]
        self._view_order = np.array(order, dtype=np.int64)
        self._viewers = self.engine.views(np.array(list(range(count)) + [v for v, _ in pairs]), self._view_order)
        self._view_env = np.zeros(len(order), dtype=np.int64)
        self._swap_row = {(v, o): count + k for k, (v, o) in enumerate(pairs)}
        self._painted: np.ndarray | None = None

    def observation_space(self, agent: AgentID) -> spaces.Box:
        return self.observation_spaces[agent]

    def action_space(self, agent: AgentID) -> spaces.Discrete:
        return self.action_spaces[agent]

    @property
    def num_agents(self) -> int:  # type: ignore[override]
        return len(self.agents)

    @property
    def max_num_agents(self) -> int:  # type: ignore[override]
        return len(self.possible_agents)

    # ------------------------------------------------------------------ episode
    def reset(
        self, seed: int | None = None, options: Mapping[str, Any] | None = None
    ) -> tuple[dict[AgentID, np.ndarray], dict[AgentID, dict]]:
        self.engine.reset(seeds=None if seed is None else [seed], options=options)  # (a bad one changes nothing)
        self.agents = list(self.possible_agents)
        views = self._paint_views()
        observations = {agent: views[self._index[agent]] for agent in self.agents}
        infos = {agent: self.engine.reset_info(0, self._index[agent]) for agent in self.agents}
        return observations, infos

    def step(self, actions: Mapping[AgentID, Any]) -> tuple[dict, dict, dict, dict, dict]:
        if not self.agents:
            raise RuntimeError("step() called with no live agents; call reset() first")
        live, index = self.agents, self._index
        values = [STAY] * self.engine.num_agents
        for agent, action in check_joint_action(actions, live, index).items():
            values[index[agent]] = action
        engine = self.engine
        events = engine.step_checked(np.array([values], dtype=np.int64))
        views = self._paint_views()
        reward, terminated, truncated = events.rewards[0].tolist(), events.terminated[0].tolist(), events.truncated[0].tolist()
        observations, rewards, terminations, truncations, infos = {}, {}, {}, {}, {}
        for agent in live:
            i = index[agent]
            observations[agent] = views[i]
            rewards[agent], terminations[agent], truncations[agent] = reward[i], terminated[i], truncated[i]
            infos[agent] = engine.step_info(events, 0, i)
        self.agents = [agent for agent in live if not (terminations[agent] or truncations[agent])]
        if not self.agents:  # the episode is over: each agent's metrics, as the leaderboard scores a learner
            for agent in live:
                metrics = engine.episode_metrics(np.zeros(1, dtype=np.int64), index[agent])
                infos[agent]["episode"] = {name: metrics[name].item() for name in (*METRIC_NAMES, "length")}
        return observations, rewards, terminations, truncations, infos

    def _paint_views(self) -> np.ndarray:
        """Paint every agent's observation and every swapped observation of the current state."""
        engine, order = self.engine, self._view_order
        self._painted = engine.paint(  # (take reads the one environment's (1, A) arrays flat)
            self._view_env,
            engine.cells.take(order),
            engine.inventory.take(order),
            engine.present.take(order),
            self._viewers,
        )
        return self._painted

    def check_action(self, agent: AgentID, action: Any) -> int:
        """``action`` as an ``int`` if ``agent`` is live and may take it, else ``ValueError``
        (what :meth:`step` checks of each action; the AEC face asks before it records one)."""
        if agent not in self.agents:
            raise ValueError(f"{agent!r} is not a live agent; agents are {self.agents}")
        return check_action(agent, action)

    # ------------------------------------------------------------------ empathy primitive
    def swapped_observation(self, viewer: AgentID, other: AgentID, in_view_only: bool = False) -> np.ndarray | None:
        """The observation ``viewer`` would get had it exchanged its situation (cell, inventory)
        with ``other``.

        ``None`` when ``other`` has left the environment, or, with ``in_view_only``, when
        ``other`` is outside ``viewer``'s window. A viewer harmed this very step still has one
        (like its final observation), as the vector env's ``swapped`` does. Unknown names raise
        ``ValueError``.
        """
        for name in (viewer, other):
            if name not in self._index:
                raise ValueError(f"unknown agent {name!r}; agents are {self.possible_agents}")
        v, o = self._index[viewer], self._index[other]
        if v == o:
            raise ValueError("an agent cannot swap places with itself")
        if self._painted is None or not self.engine.present[0, o]:
            return None
        if in_view_only and not self.engine.in_view(v, o)[0]:
            return None
        return self._painted[self._swap_row[v, o]].copy()

    # ------------------------------------------------------------------ render
    def render(self) -> str | np.ndarray | None:
        if self.render_mode is None:
            return None
        if self.render_mode == "ansi":
            return render_text(self.engine)
        return render_rgb(self.engine)

    def close(self) -> None:
        pass


class GridAECEnv(parallel_to_aec_wrapper):
    """The AEC face: ``parallel_to_aec`` over a :class:`GridParallelEnv`, except that an action is
    checked when it is given (a bad one raises ``ValueError`` and changes nothing), not when the
    last agent of the round acts."""

    def __init__(self, parallel_env: GridParallelEnv) -> None:
        super().__init__(parallel_env)
        self.agents: list[AgentID] = []

    def step(self, action: Any) -> None:
        agent = getattr(self, "agent_selection", None)
        if agent is None or not self.agents:
            raise RuntimeError("step() called with no live agents; call reset() first")
        if self.terminations[agent] or self.truncations[agent]:
            if action is not None:
                raise ValueError(f"{agent} is done (terminated or truncated): step(None) removes it, got {action!r}")
        else:
            action = self.unwrapped.check_action(agent, action)
        super().step(action)


def grid_metadata(name: str) -> dict[str, Any]:
    """The PettingZoo ``metadata`` of a gridworld named ``name``."""
    return {"name": name, "render_modes": ["ansi", "rgb_array"], "is_parallelizable": True, "render_fps": 5}


def env_constructors(raw: type[GridParallelEnv]) -> tuple[Callable[..., GridParallelEnv], Callable[..., AECEnv]]:
    """The module-level ``parallel_env`` and ``env`` (AEC, via ``parallel_to_aec``) of ``raw``."""
    name = raw.metadata["name"]

    def parallel_env(**kwargs: Any) -> GridParallelEnv:
        return raw(**_known_arguments(raw, kwargs))

    def env(**kwargs: Any) -> AECEnv:
        return GridAECEnv(raw(**_known_arguments(raw, kwargs)))

    parallel_env.__doc__ = f"``{name}`` with the parallel API (keyword arguments: see the module documentation)."
    env.__doc__ = f"``{name}`` with the AEC API (:class:`GridAECEnv`: ``parallel_to_aec`` over ``parallel_env``)."
    return parallel_env, env


def _known_arguments(raw: type[GridParallelEnv], kwargs: dict[str, Any]) -> dict[str, Any]:
    """``kwargs`` if ``raw`` takes every one (``render_mode`` and its environment's arguments),
    else :class:`~empathy_zoo.engine.arguments.UnknownArgumentError` naming those it does not
    (before Python's own ``TypeError`` of an unexpected keyword could)."""
    check_env_arguments(raw.engine_class, {key: value for key, value in kwargs.items() if key != "render_mode"})
    return kwargs
