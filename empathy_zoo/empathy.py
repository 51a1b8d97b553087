"""``EmpathyWrapper``: every live agent's ``infos`` carry the observations it would have in
the shoes of each other live agent (the perspective swap of SPEC §4)."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from gymnasium.utils import EzPickle
from pettingzoo import ParallelEnv
from pettingzoo.utils.wrappers import BaseParallelWrapper

__all__ = ["EmpathyWrapper"]


class EmpathyWrapper(BaseParallelWrapper, EzPickle):
    """Add ``infos[agent]["swapped_obs"] = {other: observation, ...}`` at reset and every step.

    Works on any ParallelEnv whose ``unwrapped`` implements
    ``swapped_observation(viewer, other, in_view_only)``. The swap is omniscient by default (as in
    the paper); with ``in_view_only=True`` an other agent appears only while it stands inside the
    viewer's window. Every agent that receives an ``infos`` entry gets one, the last step of its
    episode included (what an empathic learner needs for its final transition); agents that have
    left are never in it.
    """

    def __init__(self, env: ParallelEnv, in_view_only: bool = False) -> None:
        BaseParallelWrapper.__init__(self, env)
        EzPickle.__init__(self, env, in_view_only)
        if not hasattr(env.unwrapped, "swapped_observation"):
            raise ValueError(f"{type(env.unwrapped).__name__} does not implement swapped_observation(viewer, other)")
        self.in_view_only = bool(in_view_only)
        self._base = env.unwrapped

    def reset(self, seed: int | None = None, options: Mapping[str, Any] | None = None) -> tuple[dict, dict]:
        observations, infos = self.env.reset(seed=seed, options=options)
        return observations, self._with_swaps(infos)

    def step(self, actions: Mapping[str, Any]) -> tuple[dict, dict, dict, dict, dict]:
        observations, rewards, terminations, truncations, infos = self.env.step(actions)
        return observations, rewards, terminations, truncations, self._with_swaps(infos)

    def _with_swaps(self, infos: dict) -> dict:
        base = self._base
        out = {}
        for agent, info in infos.items():
            info = dict(info)
            if agent in base.possible_agents:
                swaps = {}
                for other in base.possible_agents:
                    if other == agent:
                        continue
                    swapped = base.swapped_observation(agent, other, in_view_only=self.in_view_only)
                    if swapped is not None:
                        swaps[other] = swapped
                info["swapped_obs"] = swaps
            out[agent] = info
        return out
