"""# Gymnasium single-agent face

One environment of the suite as a plain ``gymnasium.Env``: the learner's (robot's) view, the
fixed agents acting inside. It is a thin face over :class:`empathy_zoo.FixedAgents` around the
PettingZoo ``parallel_env``, itself a face over the engine, so the rules are the suite's own and
the same seed and actions give the same trajectory as ``FixedAgents(parallel_env())`` and as the
vector env the runner trains on. Use it to train any single-agent library (Stable-Baselines3,
CleanRL, …) on Coexistence or Sharing and still score it with the suite's metrics.

| | |
|---|---|
| Import | `from empathy_zoo.gym_adapter import make_single_agent_env` |
| Gymnasium ids | `empathy_zoo/Coexistence-v0`, `empathy_zoo/Sharing-v0` (registered on import of this module; or `gymnasium.make("empathy_zoo.gym_adapter:empathy_zoo/Coexistence-v0")`) |
| Agent | the one agent not in `fixed` (`robot_0` with the paper's fixed agents) |
| Actions | `Discrete(5)`: 0 up, 1 down, 2 left, 3 right, 4 stay |
| Observations | the agent's `Box(.., (view·view,), float32)` window, exactly as in the PettingZoo env |
| Reward | the agent's environment reward (never shaped) |

## Episode end
``terminated`` / ``truncated`` are the agent's own (SPEC §2–3): a harmed robot is terminated; a
harmed cat leaves and the robot goes on; the time limit (``max_cycles``) truncates. No
``TimeLimit`` wrapper is added: the engine truncates. Stepping after the end raises
``RuntimeError``; call ``reset``.

## Infos
The agent's PettingZoo ``infos`` entry (``harmed_by``/``harmed``, or ``batteries``) and, on the
step that ends the episode, ``info["episode_metrics"]``: the suite's episode metrics (SPEC §5:
``survival``, ``harms``, ``batteries``, ``other_batteries``, ``equality``, ``return``,
``other_return``, plus ``length``) as Python numbers, computed from what happened, never from
the reward.

## Seeding
``reset(seed=s)`` seeds the environment and its fixed agents exactly as
``FixedAgents(parallel_env()).reset(seed=s)`` does; ``reset()`` continues their streams.
``self.np_random`` is seeded too (Gymnasium's contract) but the dynamics never draw from it.

## Arguments
`SingleAgentEnv(env="coexistence_v0", fixed=None, size=None, view=None, max_cycles=None, render_mode=None, **env_options)` (`None`: the environment's default)
* `env`: `"coexistence_v0"` or `"sharing_v0"`.
* `fixed`: `{agent: policy}` (a `FixedPolicy`, a registered name or `"package.module:ClassName"`);
  `None` = the paper's (`empathy_zoo.environments.DEFAULT_POLICIES`). Exactly one agent must be left.
* `size`, `view`, `max_cycles`, `render_mode`: as for the PettingZoo env.
* `env_options`: the environment's own arguments, passed on to its PettingZoo env (Sharing:
  `start`, `inventory_encoding`); any other keyword raises `UnknownArgumentError` (a `ValueError` and a `TypeError`).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import gymnasium
import numpy as np
from gymnasium.utils import EzPickle

from empathy_zoo.environments import DEFAULT_ENVIRONMENT, FACES, GYM_IDS, default_policies
from empathy_zoo.fixed_agents import FixedAgents
from empathy_zoo.policies import FixedPolicy

__all__ = ["SingleAgentEnv", "make_single_agent_env", "GYM_IDS"]


class SingleAgentEnv(gymnasium.Env, EzPickle):
    """One learner's view of an environment of the suite (see the module documentation)."""

    # Gymnasium declares metadata an instance attribute, and __init__ replaces it per environment (never mutates it)
    metadata: dict[str, Any] = {"render_modes": ["ansi", "rgb_array"], "render_fps": 5}  # noqa: RUF012

    def __init__(
        self,
        env: str = DEFAULT_ENVIRONMENT,
        fixed: Mapping[str, FixedPolicy | str] | None = None,
        *,
        size: int | None = None,
        view: int | None = None,
        max_cycles: int | None = None,
        render_mode: str | None = None,
        **env_options: Any,
    ) -> None:
        EzPickle.__init__(self, env, fixed, size=size, view=view, max_cycles=max_cycles, render_mode=render_mode, **env_options)
        if env not in FACES:
            raise ValueError(f"unknown environment {env!r}; registered: {sorted(FACES)}")
        given = {"size": size, "view": view, "max_cycles": max_cycles}  # (None: the environment's default)
        parallel = FACES[env].parallel_env(
            render_mode=render_mode, **{k: v for k, v in given.items() if v is not None}, **env_options
        )
        self.fixed = default_policies(env, env_options) if fixed is None else dict(fixed)
        self._env = FixedAgents(parallel, self.fixed)
        if len(self._env.possible_agents) != 1:
            raise ValueError(
                f"a single-agent env needs exactly one learning agent; {env} leaves {self._env.possible_agents} "
                "(fix the others in `fixed`)"
            )
        self.agent: str = self._env.possible_agents[0]
        """The learning agent whose view this env is."""
        self._agent_index = parallel.possible_agents.index(self.agent)
        self.observation_space = parallel.observation_space(self.agent)
        self.action_space = parallel.action_space(self.agent)
        self.render_mode = render_mode
        self.metadata = {**self.metadata, "name": parallel.metadata["name"]}
        self._running = False

    def reset(self, *, seed: int | None = None, options: Mapping[str, Any] | None = None) -> tuple[np.ndarray, dict]:
        observations, infos = self._env.reset(seed=seed, options=options)  # (a bad seed or option changes nothing)
        super().reset(seed=seed)
        self._running = True
        return observations[self.agent], dict(infos[self.agent])

    def step(self, action: Any) -> tuple[np.ndarray, float, bool, bool, dict]:
        if not self._running:
            raise RuntimeError("step() called before reset() or after the episode ended; call reset()")
        observations, rewards, terminations, truncations, infos = self._env.step({self.agent: action})
        terminated, truncated = bool(terminations[self.agent]), bool(truncations[self.agent])
        info = dict(infos[self.agent])
        if terminated or truncated:
            self._running = False
            info["episode_metrics"] = self.episode_metrics()
        return observations[self.agent], float(rewards[self.agent]), terminated, truncated, info

    def episode_metrics(self) -> dict[str, int | float]:
        """The suite's metrics (SPEC §5) of the episode so far, for this env's learning agent."""
        metrics = self._env.unwrapped.engine.episode_metrics(np.array([0]), self._agent_index)
        return {name: values[0].item() for name, values in metrics.items()}

    def render(self) -> str | np.ndarray | None:
        return self._env.render()

    def close(self) -> None:
        self._env.close()


def make_single_agent_env(name: str, **kwargs: Any) -> SingleAgentEnv:
    """The single-agent Gymnasium env of ``name`` (``"coexistence_v0"``, ``"sharing_v0"``, or a
    Gymnasium id from :data:`GYM_IDS`); ``kwargs`` go to :class:`SingleAgentEnv`."""
    return SingleAgentEnv(GYM_IDS.get(name, name), **kwargs)


def _register() -> None:
    for gym_id, name in GYM_IDS.items():
        if gym_id not in gymnasium.registry:
            gymnasium.register(id=gym_id, entry_point=f"{__name__}:SingleAgentEnv", kwargs={"env": name})


_register()
