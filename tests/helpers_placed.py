"""A vector env of one environment with agents placed by hand, stepped with what the learner is told."""

from __future__ import annotations

from typing import Any

import numpy as np

from agents.step_batch import StepBatch
from empathy_zoo.training.ensemble import learner_batch
from empathy_zoo.vector import VectorEnv, VectorStep


def placed(
    env: str,
    positions: dict,
    fixed: dict,
    max_cycles: int = 500,
    in_view_only: bool = False,
    env_kwargs: dict[str, Any] | None = None,
    **options: Any,
) -> VectorEnv:
    """One environment of ``env`` with the agents at ``positions`` (and reset ``options``, e.g. batteries)."""
    venv = VectorEnv(env, 1, fixed=fixed, max_cycles=max_cycles, in_view_only=in_view_only, **(env_kwargs or {}))
    venv.reset(seed=0)
    venv.engine.reset(np.array([0]), options={"positions": positions, **options})
    venv._observations = venv._observe_learners()
    return venv


def step(venv: VectorEnv, action: int) -> tuple[VectorStep, StepBatch]:
    """The learner's ``action``: the vector env's step and the learner's batch of it."""
    obs = venv._observations[:, 0]
    actions = np.array([[action]])
    result = venv.step(actions)
    return result, learner_batch(obs, actions, result)
