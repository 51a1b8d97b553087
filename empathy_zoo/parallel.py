"""The PettingZoo ``ParallelEnv`` face of an engine with one environment."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, ClassVar

import numpy as np
from gymnasium import spaces
from gymnasium.utils import EzPickle
from pettingzoo import ParallelEnv

from empathy_zoo.engine.base import GridEngine, StepEvents
from empathy_zoo.grid import NUM_ACTIONS
from empathy_zoo.render import render_rgb, render_text

__all__ = ["GridParallelEnv"]

AgentID = str


class GridParallelEnv(ParallelEnv, EzPickle):
    """A ``ParallelEnv`` whose rules live in ``engine_class`` (stepping one environment)."""

    engine_class: ClassVar[type[GridEngine]]
    metadata: ClassVar[dict[str, Any]]

    def __init__(self, size: int = 7, view: int = 5, max_cycles: int = 500, render_mode: str | None = None) -> None:
        EzPickle.__init__(self, size=size, view=view, max_cycles=max_cycles, render_mode=render_mode)
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(f"render_mode must be one of {self.metadata['render_modes']} or None, got {render_mode!r}")
        self.render_mode = render_mode
        self.engine = self.engine_class(1, size=size, view=view, max_cycles=max_cycles)
        self.possible_agents: list[AgentID] = list(self.engine.agents)
        self.agents: list[AgentID] = []
        obs_space = spaces.Box(
            low=np.float32(self.engine.obs_low), high=np.float32(self.engine.obs_high),
            shape=(self.engine.obs_size,), dtype=np.float32,
        )
        self.observation_spaces = {agent: obs_space for agent in self.possible_agents}
        self.action_spaces = {agent: spaces.Discrete(NUM_ACTIONS) for agent in self.possible_agents}
        self._index = {agent: i for i, agent in enumerate(self.possible_agents)}

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
        try:
            self.engine.reset(seeds=None if seed is None else [seed], options=options)
        except ValueError:
            self.engine.running[:] = False
            self.agents = []
            raise
        self.agents = list(self.possible_agents)
        observations = {agent: self.engine.observe(self._index[agent])[0] for agent in self.agents}
        infos = {agent: self.engine.reset_info(0, self._index[agent]) for agent in self.agents}
        return observations, infos

    def step(self, actions: Mapping[AgentID, Any]) -> tuple[dict, dict, dict, dict, dict]:
        if not self.agents:
            raise RuntimeError("step() called with no live agents; call reset() first")
        array = np.full((1, self.engine.num_agents), 4, dtype=np.int64)
        for agent, action in actions.items():
            if agent not in self._index:
                raise ValueError(f"action given for unknown agent {agent!r}; agents are {self.agents}")
            if agent not in self.agents:
                raise ValueError(f"action given for {agent!r}, which is no longer in the environment")
            array[0, self._index[agent]] = self._check_action(agent, action)
        missing = [agent for agent in self.agents if agent not in actions]
        if missing:
            raise ValueError(f"no action given for live agent(s) {missing}")
        events = self.engine.step(array)
        live = self.agents
        observations = {agent: self.engine.observe(self._index[agent])[0] for agent in live}
        rewards = {agent: float(events.rewards[0, self._index[agent]]) for agent in live}
        terminations = {agent: bool(events.terminated[0, self._index[agent]]) for agent in live}
        truncations = {agent: bool(events.truncated[0, self._index[agent]]) for agent in live}
        infos = {agent: self.engine.step_info(events, 0, self._index[agent]) for agent in live}
        self.agents = [agent for agent in live if not (terminations[agent] or truncations[agent])]
        return observations, rewards, terminations, truncations, infos

    def _check_action(self, agent: AgentID, action: Any) -> int:
        value = np.asarray(action)
        if value.shape != () or not np.issubdtype(value.dtype, np.integer):
            raise ValueError(f"action for {agent} must be an integer in [0, {NUM_ACTIONS}), got {action!r}")
        if not 0 <= int(value) < NUM_ACTIONS:
            raise ValueError(f"action {int(value)} for {agent} is outside Discrete({NUM_ACTIONS})")
        return int(value)

    # ------------------------------------------------------------------ empathy primitive
    def swapped_observation(self, viewer: AgentID, other: AgentID, in_view_only: bool = False) -> np.ndarray | None:
        """The observation ``viewer`` would get had it exchanged cell and inventory with ``other``.

        ``None`` when ``other`` has left the environment, or, with ``in_view_only``, when
        ``other`` is outside ``viewer``'s window. Unknown names raise ``ValueError``.
        """
        for name in (viewer, other):
            if name not in self._index:
                raise ValueError(f"unknown agent {name!r}; agents are {self.possible_agents}")
        v, o = self._index[viewer], self._index[other]
        if v == o:
            raise ValueError("an agent cannot swap places with itself")
        if not self.engine.present[0, o] or not self.engine.present[0, v]:
            return None
        if in_view_only and not self.engine.in_view(v, o)[0]:
            return None
        return self.engine.observe_swapped(v, o)[0]

    # ------------------------------------------------------------------ render
    def render(self) -> str | np.ndarray | None:
        if self.render_mode is None:
            return None
        if self.render_mode == "ansi":
            return render_text(self.engine)
        return render_rgb(self.engine)

    def close(self) -> None:
        pass
