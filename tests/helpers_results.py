"""Synthetic result files for the leaderboard's and the verdicts' tests."""

from __future__ import annotations

from dataclasses import asdict

import numpy as np

from agents.settings import EmpathicDQNSettings
from empathy_zoo.environments import DEFAULT_POLICIES
from empathy_zoo.metrics import METRIC_NAMES

SETTINGS = {"learning_starts": 100, "epsilon_decay_steps": 3900}
"""Schedule of the synthetic runs: 4,000 steps, ε at its floor on the last one."""


def synthetic_result(env: str, method: str, beta: float, seed: int, fixed: dict | None = None, **means: float) -> dict:
    rng = np.random.default_rng(seed)
    episodes = 40
    train = {"episode_end_step": list(range(100, 100 * (episodes + 1), 100))}
    for metric in METRIC_NAMES:
        centre = means.get(metric, 0.0)
        train[metric] = (centre + rng.normal(0, 0.01, episodes)).tolist()
    settings = asdict(EmpathicDQNSettings(selfishness=beta, **SETTINGS))
    return {
        "schema": 1,
        "run_id": f"{env}__{method}-{beta}__s{seed}",
        "env": env,
        "method": method,
        "method_label": f"{method} {beta}",
        "seed": seed,
        "steps": 4000,
        "config": {
            "settings": settings,
            "variant": env,
            "env_kwargs": {},
            "fixed": dict(DEFAULT_POLICIES[env] if fixed is None else fixed),
        },
        "train": train,
        "eval": [{"step": 4000, **{m: [means.get(m, 0.0) + 0.01 * seed] * 3 for m in METRIC_NAMES}}],
    }
