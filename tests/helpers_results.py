"""Synthetic result files for the leaderboard's and the verdicts' tests: documents as a file holds
them (:func:`synthetic_document`), and runs as the suite reads them (:func:`synthetic_result`,
:func:`record`: through the result-file checker, into a :class:`~empathy_zoo.experiment.records.RunResult`)."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Sequence
from dataclasses import asdict
from types import MappingProxyType

import numpy as np

from agents.settings import EmpathicDQNSettings
from baselines.registry import METHODS
from empathy_zoo.environments import DEFAULT_POLICIES
from empathy_zoo.experiment.records import RunResult, read_only_series
from empathy_zoo.experiment.result_reader import check_result
from empathy_zoo.metrics import INTEGER_METRICS, METRIC_NAMES, METRIC_RANGES
from empathy_zoo.result_file import episode_bounds
from empathy_zoo.run_ids import run_id

SETTINGS = {"learning_starts": 500, "epsilon_decay_steps": 19_500}
"""Schedule of the synthetic runs: 20,000 steps (:data:`SYNTHETIC_STEPS`), ε at its floor on the last one."""


SCHEMA_1_SHAPING = {"dqn_harm_penalty": {"harm_penalty": -100.0}, "dqn_equality": {"equality_shaping": True}}
"""How the schema-1 files of the shaped baselines hold their shaping (as settings)."""


def hand_made_result(
    env: str,
    method: str,
    seed: int,
    train: dict[str, list],
    evaluations: list[dict],
    *,
    label: str | None = None,
    steps: int | None = None,
    settings: dict | None = None,
    env_kwargs: dict | None = None,
) -> RunResult:
    """A run of the given training columns (``episode_end_step`` and some metrics) and evaluations
    (``step`` and some metrics), the metrics they leave out 0 per episode (equality 1), in the
    world of ``env_kwargs``, as a schema-1 file of ``method`` with ``settings`` (a shaped
    baseline's shaping added: :data:`SCHEMA_1_SHAPING`) holds them, read through the checker: for
    tests of the statistics on runs of chosen values."""
    label = label if label is not None else f"{method} {(settings or {}).get('selfishness', 1.0)}"
    episodes = len(train["episode_end_step"])

    def filled(columns: dict, count: int) -> dict:
        return {name: columns.get(name, [1.0 if name == "equality" else 0] * count) for name in METRIC_NAMES}

    last = evaluations[-1] if evaluations else {}
    count = len(next((v for k, v in last.items() if k != "step"), []))
    document = schema_1_document(
        env,
        method,
        label,
        seed,
        steps if steps is not None else max([*train["episode_end_step"], *(e["step"] for e in evaluations), 1]),
        {
            "settings": {**(settings or {}), **SCHEMA_1_SHAPING.get(method, {})},
            "env_kwargs": dict(env_kwargs or {}),
            "fixed": dict(DEFAULT_POLICIES[env]),
            "label": label,
        },
        {"episode_end_step": list(train["episode_end_step"]), **filled(train, episodes)},
        [{"step": e["step"], **filled(e, count)} for e in evaluations],
    )
    return RunResult.from_checked(as_schema_3(document))


def schema_1_document(
    env: str, method: str, label: str, seed: int, steps: int, config: dict, train: dict, evaluations: list, **more: object
) -> dict:
    """A schema-1 result document of these fields (and ``more`` top-level ones), under the run id
    its config gives (:func:`derive_run_id`)."""
    return derive_run_id(
        {
            "schema": 1,
            "run_id": "(derived below)",
            "env": env,
            "method": method,
            "method_label": label,
            "seed": seed,
            "steps": steps,
            "config": config,
            "train": train,
            "eval": evaluations,
            **more,
        }
    )


def as_schema_3(document: dict, path: str = "synthetic.json") -> dict:
    """``document`` (any schema) checked as the suite reads it, then under the run id its checked
    config gives: a schema-3 document a file may hold (an upgrade adds to the config the id was
    made of, so a schema-1 document's id is not the one its upgrade gives)."""
    return check_result(derive_run_id(check_result(derive_run_id(document), path)), path)


def derive_run_id(document: dict) -> dict:
    """``document`` (changed in place) with the run id its config gives, as the trainer names a
    run (:func:`~empathy_zoo.run_ids.run_id`; the result-file checker recomputes it)."""
    config = document["config"]
    variant = config.get("variant") or document.get("variant") or document["env"]
    document["run_id"] = run_id(variant, document["method"], config, document["seed"])
    return document


def edited(run: RunResult, change: Callable[[dict], object]) -> RunResult:
    """``run`` with ``change`` made to its document (in place), read again through the checker;
    unless ``change`` sets the run id, the id is the one the changed config gives."""
    document = run.to_document()
    change(document)
    return record(derive_run_id(document) if document["run_id"] == run.run_id else document)


def with_training(run: RunResult, **columns: Sequence[float]) -> RunResult:
    """``run`` with the training columns ``columns`` (``episode_end_step`` or metrics) in place of
    its own: a record made in code, not read (a file may not hold it: episodes past the run's
    steps, a fractional count, columns of different lengths), for tests of a reader's own checks."""
    ends = columns.pop("episode_end_step", None)
    train = dataclasses.replace(
        run.train,
        episode_end_step=run.train.episode_end_step if ends is None else read_only_series(ends),
        metrics=MappingProxyType({**run.train.metrics, **{k: read_only_series(v) for k, v in columns.items()}}),
    )
    return dataclasses.replace(run, train=train)


def record(document: dict, path: str = "synthetic.json") -> RunResult:
    """``document`` (a result document) read as the suite reads a file: checked
    (:func:`~empathy_zoo.experiment.result_reader.check_result`), then a record."""
    return RunResult.from_checked(check_result(document, path))


def synthetic_result(env: str, method: str, beta: float, seed: int, fixed: dict | None = None, **means: float) -> RunResult:
    """The record of :func:`synthetic_document`: a run as the leaderboard reads it."""
    return RunResult.from_checked(synthetic_document(env, method, beta, seed, fixed, **means))


def synthetic_document(env: str, method: str, beta: float, seed: int, fixed: dict | None = None, **means: float) -> dict:
    """A schema-3 result (a schema-1 document, read as the suite reads it) with ``means`` per metric.
    A method whose reward transform no schema-1 file held (the Lagrangian, Be Considerate, ...)
    gets DQN's document with its own method, reward record and description, as it records them."""
    own = METHODS[method].reward if method in METHODS else None
    if own is None or method in SCHEMA_1_SHAPING:
        return as_schema_3(synthetic_schema_1(env, method, beta, seed, fixed, **means))
    document = check_result(synthetic_schema_1(env, "dqn", beta, seed, fixed, **means), "synthetic.json")
    registered = METHODS[method]
    reward = registered.make_reward({})
    settings = registered.make_settings(dict(document["config"]["settings"]))
    document.update(method=method, method_label=f"{method} {beta}")
    document["config"] = {
        **document["config"],
        "reward": {"name": reward.name, **asdict(reward)},
        "description": registered.describe(settings, reward),
    }
    return as_schema_3(document)


MAX_CYCLES = 500
"""The episode length of every synthetic run (the environments' default ``max_cycles``)."""


def bounded(metric: str) -> tuple[float, float | None]:
    """The range of ``metric`` in a synthetic run: its own, survival at most :data:`MAX_CYCLES`."""
    low, high = METRIC_RANGES[metric]
    return low, float(MAX_CYCLES) if metric == "survival" else high


SYNTHETIC_STEPS = 20_000
"""The training budget of every synthetic run: 40 episodes of :data:`MAX_CYCLES` steps."""

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
    """The result of :func:`synthetic_document` as a schema-1 file holds it."""
    rng = np.random.default_rng(seed)
    episodes = SYNTHETIC_STEPS // MAX_CYCLES  # (40 whole episodes of max_cycles: any survival fits in them)
    train = {"episode_end_step": list(range(MAX_CYCLES, SYNTHETIC_STEPS + 1, MAX_CYCLES))}
    for metric in METRIC_NAMES:
        centre = means.get(metric, 0.0)
        low, high = bounded(metric)
        if metric in INTEGER_METRICS:
            train[metric] = whole_episodes(centre + rng.normal(0, 0.01), episodes, rng, metric)
        else:
            train[metric] = np.clip(centre + rng.normal(0, 0.01, episodes), low, high).tolist()  # (within what an episode gives)
    evaluation = {m: greedy_episodes(means.get(m, 0.0) + 0.01 * seed, rng, m) for m in METRIC_NAMES}
    settings = asdict(EmpathicDQNSettings(selfishness=beta, **SETTINGS)) | SCHEMA_1_SHAPING.get(method, {})
    return derive_run_id(
        {
            "schema": 1,
            "run_id": "(derived below)",
            "env": env,
            "method": method,
            "method_label": f"{method} {beta}",
            "seed": seed,
            "steps": SYNTHETIC_STEPS,
            "config": {
                "settings": settings,
                "variant": env,
                "env_kwargs": {},
                "fixed": dict(DEFAULT_POLICIES[env] if fixed is None else fixed),
            },
            "train": within_env(env, train),
            "eval": [{"step": SYNTHETIC_STEPS, **within_env(env, evaluation)}],
        }
    )


def within_env(env: str, columns: dict) -> dict:
    """``columns`` (metric values of episodes of ``env`` at its defaults) with each count capped at
    the most an episode of ``env`` holds (:func:`~empathy_zoo.result_file.episode_bounds`): no harm
    where no one can be harmed, no battery where there is none. Drawn first, capped after, so the
    random draws of every other value are those of an uncapped run."""
    bounds = episode_bounds(env, {})
    return {
        name: values if bounds.get(name) is None else [min(value, bounds[name]) for value in values]
        for name, values in columns.items()
    }


def within_episodes(end_steps: list[int], columns: dict) -> dict:
    """Training ``columns`` with each episode's survival capped at its own length (its end step
    less the one before: the result-file checker refuses a robot operative past its episode's end)."""
    lengths = [end - start for start, end in zip([0, *end_steps], end_steps, strict=False)]
    return columns | {"survival": [min(value, length) for value, length in zip(columns["survival"], lengths, strict=True)]}
