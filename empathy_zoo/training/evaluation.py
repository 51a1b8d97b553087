"""Greedy evaluation (ε = 0) of every run of an ensemble, on fixed start seeds."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from empathy_zoo.metrics import METRIC_NAMES
from empathy_zoo.policies import PolicyEntry
from empathy_zoo.randomness import STREAMS, derive_key
from empathy_zoo.vector import VectorEnv

__all__ = ["evaluate_greedy", "STREAM_EVAL"]

STREAM_EVAL = STREAMS["eval_env"]


def evaluate_greedy(
    learner: Any,
    env: str,
    seeds: Sequence[int],
    episodes: int,
    fixed: Mapping[str, PolicyEntry],
    env_kwargs: dict[str, Any],
    stream: int = STREAM_EVAL,
) -> list[dict[str, list]]:
    """Play ``episodes`` greedy episodes per run; returns per run a dict of metric columns.

    Start states come from seeds derived from each run's seed (``derive_key(seed, stream, e)``
    for episode ``e``; ``stream`` is the training's evaluation stream unless another is given), so
    every evaluation of a run starts from the same states and the runs' evaluations are
    independent of each other.
    """
    k = len(seeds)
    venv = VectorEnv(env, k * episodes, fixed=fixed, **env_kwargs)
    obs = venv.reset(seed=[derive_key(s, stream, e) for s in seeds for e in range(episodes)])
    done = np.zeros(k * episodes, dtype=bool)
    columns: dict[str, np.ndarray] = {name: np.zeros(k * episodes) for name in METRIC_NAMES}
    while not done.all():
        actions = learner.act(obs[:, 0].reshape(k, episodes, -1), greedy=True).reshape(-1, 1)
        step = venv.step(actions)
        ids = step.finished["env"]
        obs = step.observations
        if ids.size == 0:
            continue
        fresh = ids[~done[ids]]
        mask = ~done[ids]
        for name in METRIC_NAMES:
            columns[name][fresh] = step.finished[name][mask]
        done[fresh] = True
    return [{name: columns[name][r * episodes : (r + 1) * episodes].tolist() for name in METRIC_NAMES} for r in range(k)]
