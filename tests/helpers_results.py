"""Synthetic result files for the leaderboard's and the verdicts' tests."""

from __future__ import annotations

from dataclasses import asdict

import numpy as np

from agents.settings import EmpathicDQNSettings
from baselines.registry import METHODS
from empathy_zoo.environments import DEFAULT_POLICIES
from empathy_zoo.experiment.result_reader import check_result
from empathy_zoo.metrics import INTEGER_METRICS, METRIC_NAMES, METRIC_RANGES
from empathy_zoo.result_file import schema_2_description

SETTINGS = {"learning_starts": 100, "epsilon_decay_steps": 3900}
"""Schedule of the synthetic runs: 4,000 steps, ε at its floor on the last one."""


SCHEMA_1_SHAPING = {"dqn_harm_penalty": {"harm_penalty": -100.0}, "dqn_equality": {"equality_shaping": True}}
"""How the schema-1 files of the shaped baselines hold their shaping (as settings)."""


def described(run: dict) -> dict:
    """A hand-made run dict with the ``config.description`` its method name has at schema 2 (as
    reading an older file gives it): for runs handed to the leaderboard without a file."""
    run["config"] = {**run.get("config", {}), "description": schema_2_description(run["method"], run.get("config", {}))}
    return run


def synthetic_result(env: str, method: str, beta: float, seed: int, fixed: dict | None = None, **means: float) -> dict:
    """A schema-3 result (a schema-1 document, read as the suite reads it) with ``means`` per metric.
    A method whose reward transform no schema-1 file held (the Lagrangian, Be Considerate, ...)
    gets DQN's document with its own method, reward record and description, as it records them."""
    own = METHODS[method].reward if method in METHODS else None
    if own is None or method in SCHEMA_1_SHAPING:
        return check_result(synthetic_schema_1(env, method, beta, seed, fixed, **means), "synthetic.json")
    document = check_result(synthetic_schema_1(env, "dqn", beta, seed, fixed, **means), "synthetic.json")
    registered = METHODS[method]
    reward = registered.make_reward({})
    settings = registered.make_settings(dict(document["config"]["settings"]))
    document.update(method=method, method_label=f"{method} {beta}", run_id=f"{env}__{method}-{beta}__s{seed}")
    document["config"] = {
        **document["config"],
        "reward": {"name": reward.name, **asdict(reward)},
        "description": registered.describe(settings, reward),
    }
    return check_result(document, "synthetic.json")


MAX_CYCLES = 500
"""The episode length of every synthetic run (the environments' default ``max_cycles``)."""


def bounded(metric: str) -> tuple[float, float | None]:
    """The range of ``metric`` in a synthetic run: its own, survival at most :data:`MAX_CYCLES`."""
    low, high = METRIC_RANGES[metric]
    return low, float(MAX_CYCLES) if metric == "survival" else high


EVAL_EPISODES = 100
"""Greedy episodes per evaluation of a synthetic run: a mean of counts is then exact to 0.01."""


def whole_episodes(mean: float, episodes: int, rng: np.random.Generator, metric: str) -> list[float]:
    """``episodes`` whole-number values of the count ``metric`` (within its range) whose mean is
    ``mean`` to within ``1 / episodes``: each episode ``floor(mean)`` or one more, in ``rng``'s order."""
    low, high = bounded(metric)
    mean = float(np.clip(mean, low, high))
    base = int(np.floor(mean))
    # (mean may be a NumPy scalar: int() keeps a Python int whatever round() gives back)
    more = min(int(round((mean - base) * episodes)), episodes) if high is None or base < high else 0  # noqa: RUF046
    values = np.array([base + 1] * more + [base] * (episodes - more), dtype=float)
    return rng.permutation(values).tolist()


def greedy_episodes(mean: float, rng: np.random.Generator, metric: str) -> list[float]:
    """The :data:`EVAL_EPISODES` greedy episodes of one evaluation, of mean ``mean`` (clipped to its range)."""
    if metric in INTEGER_METRICS:
        return whole_episodes(mean, EVAL_EPISODES, rng, metric)
    return [float(np.clip(mean, *bounded(metric)))] * EVAL_EPISODES


def synthetic_schema_1(env: str, method: str, beta: float, seed: int, fixed: dict | None = None, **means: float) -> dict:
    """The result of :func:`synthetic_result` as a schema-1 file holds it."""
    rng = np.random.default_rng(seed)
    episodes = 40
    train = {"episode_end_step": list(range(100, 100 * (episodes + 1), 100))}
    for metric in METRIC_NAMES:
        centre = means.get(metric, 0.0)
        low, high = bounded(metric)
        if metric in INTEGER_METRICS:
            train[metric] = whole_episodes(centre + rng.normal(0, 0.01), episodes, rng, metric)
        else:
            train[metric] = np.clip(centre + rng.normal(0, 0.01, episodes), low, high).tolist()  # (within what an episode gives)
    settings = asdict(EmpathicDQNSettings(selfishness=beta, **SETTINGS)) | SCHEMA_1_SHAPING.get(method, {})
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
        "eval": [{"step": 4000, **{m: greedy_episodes(means.get(m, 0.0) + 0.01 * seed, rng, m) for m in METRIC_NAMES}}],
    }
