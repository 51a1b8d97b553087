"""Hand-made evaluation files (``empathy-zoo evaluate``'s) for the held-out section's tests: per
run and scenario, the per-episode values of every metric are given, so each verdict is known."""

from __future__ import annotations

import hashlib
import shutil
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
from helpers_results import record, synthetic_document, whole_episodes

from empathy_zoo.atomic import write_json_atomic
from empathy_zoo.evaluation_file import FORMAT, SCHEMA, TRAINED_WITH, check_evaluation, evaluation_path
from empathy_zoo.experiment.records import RunResult
from empathy_zoo.metrics import INTEGER_METRICS, METRIC_NAMES
from empathy_zoo.randomness import STREAMS

EPISODES = 100
"""Episodes per scenario of every synthetic evaluation: a count given as a mean is exact to 0.01."""


def scenario_set(env: str, scenarios: Mapping[str, Mapping[str, str]], name: str = "synthetic") -> dict[str, Any]:
    """A set's definition: ``{scenario: fixed}``, each with a reason; a scenario of several fixed
    agents sets the engine's count argument to their number (``num_cats = 3``)."""
    from empathy_zoo.environments import ENGINES

    count = ENGINES[env].count_argument

    def arguments(fixed: Mapping[str, str]) -> dict[str, Any]:
        return {count: len(fixed)} if count and len(fixed) > 1 else {}

    return {
        "name": name,
        "env": env,
        "description": "Hand-made partners.",
        "scenarios": [
            {"name": s, "reason": f"Why {s}.", "env_kwargs": arguments(f), "fixed": dict(f)} for s, f in scenarios.items()
        ],
    }


def sha_of(run_id: str) -> str:
    return hashlib.sha256(run_id.encode()).hexdigest()


def synthetic_run(env: str, method: str, beta: float, seed: int) -> RunResult:
    """A result (as :func:`leaderboard.aggregate.load_results` gives it) that kept an agent (its
    document, to write to a file: ``run.to_document()``)."""
    run = synthetic_document(env, method, beta, seed)
    run["agent"] = {"file": f"{run['run_id']}.agent.pt", "sha256": sha_of(run["run_id"])}
    return record(run)


def synthetic_evaluation(
    run: RunResult,
    definition: Mapping[str, Any],
    values: Mapping[str, Mapping[str, float | Sequence[float]]],
    own_fixed: Mapping[str, str],
) -> dict[str, Any]:
    """The evaluation file of ``run`` in the set ``definition``: ``values[scenario][metric]`` is the
    mean of the episodes (a number: a count's episodes are whole numbers, ``floor`` or one more) or
    the episodes' values; metrics not given are 0."""

    def metrics(scenario: str) -> dict[str, list[float]]:
        given = values.get(scenario, {})
        out = {}
        for metric in METRIC_NAMES:
            value = given.get(metric, 0.0)
            if isinstance(value, Sequence):
                out[metric] = [float(v) for v in value]
            elif metric in INTEGER_METRICS:
                out[metric] = whole_episodes(float(value), EPISODES, np.random.default_rng(0), metric)
            else:
                out[metric] = [float(value)] * EPISODES
        return out

    scenarios = [
        {
            "name": TRAINED_WITH,
            "reason": "Own.",
            "held_out": False,
            "env_kwargs": {},
            "fixed": dict(own_fixed),
            "metrics": metrics(TRAINED_WITH),
        }
    ]
    for entry in definition["scenarios"]:
        scenarios.append({**entry, "held_out": dict(entry["fixed"]) != dict(own_fixed), "metrics": metrics(entry["name"])})
    document = {
        "format": FORMAT,
        "schema": SCHEMA,
        "version": "0.4.0",
        "run_id": run.run_id,
        "env": run.env,
        "variant": run.env,
        "method": run.method,
        "method_label": run.method_label,
        "seed": run.seed,
        "agent": None if run.agent is None else run.agent.to_document(),
        "scenario_set": dict(definition),
        "episodes": EPISODES,
        "stream": STREAMS["heldout_eval"],
        "scenarios": scenarios,
    }
    return check_evaluation(document, "synthetic evaluation")


def write_synthetic(
    out: Path,
    runs_and_values: Sequence[tuple[RunResult, Mapping[str, Any]]],
    definition: Mapping[str, Any],
    own_fixed: Mapping[str, str],
) -> list[Path]:
    """Write the evaluation files of ``(run, values)`` pairs under ``out/evaluations/<set>/``."""
    paths = []
    for run, values in runs_and_values:
        path = evaluation_path(out, definition["name"], run.run_id)
        paths.append(write_json_atomic(path, synthetic_evaluation(run, definition, values, own_fixed)))
    return paths


def dqn_and_empathic_runs(seeds: Sequence[int], max_cycles: int, eval_episodes: int) -> list[Any]:
    """Tiny runs kept agents can be read from: DQN and Empathic DQN (β = 0.5) on Coexistence,
    600 steps of episodes of at most ``max_cycles`` steps, one greedy evaluation at the end."""
    from helpers_resume import SMALL_SETTINGS

    from empathy_zoo.experiment import RunSpec

    methods: dict[str, dict[str, Any]] = {"dqn": {}, "empathic_dqn": {"selfishness": 0.5}}
    return [
        RunSpec.of(
            env="coexistence_v0",
            method=method,
            settings={**SMALL_SETTINGS, **extra},
            steps=600,
            eval_interval=600,
            eval_episodes=eval_episodes,
            env_kwargs={"max_cycles": max_cycles},
            seed=seed,
        )
        for method, extra in methods.items()
        for seed in seeds
    ]


POPULATIONS = Path(__file__).resolve().parents[1] / "docs" / "results" / "populations"
"""The shipped population-trained runs (``default_trained`` within: the default-trained ones)."""


def population_dirs(tmp_path: Path) -> tuple[Path, Path]:
    """The shipped population-trained and default-trained Coexistence runs and their test-split
    evaluations, copied into ``tmp_path`` (agent files left out: population-reading opens none)."""
    population, default = tmp_path / "population", tmp_path / "default"
    for source, target in ((POPULATIONS, population), (POPULATIONS / "default_trained", default)):
        (target / "evaluations").mkdir(parents=True)
        shutil.copytree(
            source / "runs",
            target / "runs",
            ignore=shutil.ignore_patterns("*.agent.*", "sharing*", "charger*", "helping*", "vase*"),
        )
        shutil.copytree(source / "evaluations" / "coexistence_v0_test", target / "evaluations" / "coexistence_v0_test")
    return population, default
