"""Leaderboard computation on hand-computed data: selection, means, intervals, curves."""

from __future__ import annotations

import dataclasses
import json
import math
from pathlib import Path
from types import MappingProxyType
from typing import Any

import numpy as np
import pytest
from helpers_results import derive_run_id, record, schema_1_document, within_env

from empathy_zoo.experiment.records import RunResult, read_only_series
from empathy_zoo.metrics import METRIC_NAMES
from leaderboard.aggregate import (
    bootstrap_mean_ci,
    final_episode_count,
    group_runs,
    learning_curves,
    load_results,
    mean_ci,
    result_files,
    rolling_curve,
    run_scalars,
    score_runs,
    student_t_interval,
    student_t_quantile,
    t_level,
)

T_9875_2 = 6.205346816570706
"""t(0.9875, 2 degrees of freedom), from mpmath: the quantile of the leaderboard's 3-seed interval."""


def make_document(
    env: str,
    label: str,
    seed: int,
    survival: list[float],
    *,
    eval_survival: list[float] | None = None,
    end_steps: list[int] | None = None,
    steps: int = 100,
    method: str = "dqn",
) -> dict[str, Any]:
    """A schema-1 result document whose every metric column equals ``survival`` (train) /
    ``eval_survival`` (equality within its range: at most 1; a count within what an episode of
    ``env`` holds: :func:`~helpers_results.within_env`)."""
    n = len(survival)
    end_steps = end_steps if end_steps is not None else [int((i + 1) * steps / n) for i in range(n)]

    def column(values: list[float], metric: str) -> list[float]:
        values = within_env(env, {metric: values})[metric]
        return [min(value, 1.0) for value in values] if metric == "equality" else list(values)

    train: dict[str, Any] = {"episode_end_step": end_steps}
    train.update({metric: column(survival, metric) for metric in METRIC_NAMES})
    evaluations = []
    if eval_survival is not None:
        evaluations.append({"step": steps, **{metric: column(eval_survival, metric) for metric in METRIC_NAMES}})
    return schema_1_document(
        env,
        method,
        label,
        seed,
        steps,
        {"settings": {}, "env_kwargs": {}, "fixed": {}},
        train,
        evaluations,
        wall_time_s=0.0,
        version="0.1.0",
        commit=None,
        created="2026-01-01T00:00:00+00:00",
    )


def make_run(env: str, label: str, seed: int, survival: list[float], **options: Any) -> RunResult:
    """The run of :func:`make_document`, read as the leaderboard reads a file."""
    return record(make_document(env, label, seed, survival, **options))


def t_by_hand(values: list[float], quantile: float) -> tuple[float, float]:
    """mean ± quantile · s / √n, with s the n − 1 standard deviation, in plain Python."""
    n = len(values)
    mean = sum(values) / n
    s = math.sqrt(sum((v - mean) ** 2 for v in values) / (n - 1))
    return mean - quantile * s / math.sqrt(n), mean + quantile * s / math.sqrt(n)


def bootstrap_by_hand(values: np.ndarray, seed: int, n_resamples: int, confidence: float = 0.95) -> tuple[float, float]:
    rng = np.random.default_rng(seed)
    indices = rng.integers(0, len(values), size=(n_resamples, len(values)))
    means = values[indices].mean(axis=1)
    tail = 100 * (1 - confidence) / 2
    low, high = np.percentile(means, [tail, 100 - tail])
    return float(low), float(high)


@pytest.mark.parametrize(("n", "expected"), [(0, 0), (1, 1), (9, 1), (10, 1), (11, 2), (30, 3), (100, 10), (101, 11)])
def test_final_episode_count_is_ceil_of_ten_percent_at_least_one(n: int, expected: int) -> None:
    assert final_episode_count(n) == expected


def test_run_scalars_select_final_ten_percent_and_last_evaluation() -> None:
    survival = [float(i) for i in range(1, 21)]  # (20 episodes of 20 steps: each survives at most its length)
    document = make_document("coexistence_v0", "DQN", 0, survival, eval_survival=[1.0, 3.0], steps=400)
    earlier = {metric: [1.0 if metric == "equality" else 100.0] * 2 for metric in METRIC_NAMES}
    document["eval"].insert(0, {"step": 50, **within_env("coexistence_v0", earlier)})
    scalars = run_scalars(record(document))  # (the last evaluation: that of the latest step)
    assert scalars["train_final10"]["survival"] == 19.5  # episodes 19 and 20 of 20
    assert scalars["eval"]["survival"] == 2.0  # (the mean of 1 and 3, not the earlier 100)


def test_run_scalars_are_nan_without_episodes_or_evaluation() -> None:
    run = make_run("coexistence_v0", "DQN", 0, [])
    scalars = run_scalars(run)
    assert math.isnan(scalars["train_final10"]["survival"]) and math.isnan(scalars["eval"]["survival"])


def test_run_scalars_ignore_nan_episodes() -> None:
    """No result file holds a NaN (the checker refuses one), but a record made in code may."""
    run = make_run("coexistence_v0", "DQN", 0, [5.0] * 20)
    survival = read_only_series([5.0] * 18 + [float("nan"), 7.0])
    train = dataclasses.replace(run.train, metrics=MappingProxyType({**run.train.metrics, "survival": survival}))
    assert run_scalars(dataclasses.replace(run, train=train))["train_final10"]["survival"] == 7.0


def test_bootstrap_identical_seeds_give_a_zero_width_interval() -> None:
    mean, low, high = bootstrap_mean_ci([3.5, 3.5, 3.5])
    assert mean == low == high == 3.5


def test_bootstrap_single_seed_interval_is_the_point() -> None:
    mean, low, high = bootstrap_mean_ci([[2.0, 4.0]])
    assert mean.tolist() == low.tolist() == high.tolist() == [2.0, 4.0]


def test_bootstrap_matches_a_direct_numpy_percentile_bootstrap() -> None:
    values = np.array([1.0, 2.0, 4.0, 8.0, 16.0])
    mean, low, high = bootstrap_mean_ci(values, random_state=np.random.default_rng(7), n_resamples=500)
    expected_low, expected_high = bootstrap_by_hand(values, 7, 500)
    assert mean == pytest.approx(6.2)
    assert low == pytest.approx(expected_low, rel=1e-12) and high == pytest.approx(expected_high, rel=1e-12)
    assert low < mean < high


def test_bootstrap_with_an_int_seed_is_deterministic_and_columnwise() -> None:
    table = np.array([[1.0, 10.0], [2.0, 30.0], [6.0, 20.0]])
    mean, low, high = bootstrap_mean_ci(table, random_state=3, n_resamples=300)
    for j in range(2):
        assert (low[j], high[j]) == pytest.approx(bootstrap_by_hand(table[:, j], 3, 300), rel=1e-12)
    assert mean.tolist() == [3.0, 20.0]
    again = bootstrap_mean_ci(table, random_state=3, n_resamples=300)
    assert np.array_equal(again[1], low) and np.array_equal(again[2], high)


def test_bootstrap_rejects_no_seeds() -> None:
    with pytest.raises(ValueError, match="at least one seed"):
        bootstrap_mean_ci([])


@pytest.mark.parametrize(
    ("probability", "df", "expected"),
    [
        (0.975, 2, 0.95 / math.sqrt(2 * 0.975 * 0.025)),  # df = 2 in closed form: (2p − 1) / √(2p(1 − p))
        (0.975, 1, math.tan(math.pi * 0.475)),  # Cauchy
        (0.975, 4, 2.7764451051977935),
        (0.975, 9, 2.262157162798205),
        (0.9875, 4, 3.4954059325164416),  # mpmath
        (0.025, 3, -3.182446305284263),
        (0.5, 7, 0.0),
    ],
)
def test_student_t_quantile_matches_closed_forms_and_mpmath(probability: float, df: int, expected: float) -> None:
    assert student_t_quantile(probability, df) == pytest.approx(expected, rel=1e-12, abs=1e-15)


def test_student_t_quantile_rejects_bad_input() -> None:
    for probability, df in ((0.0, 3), (1.0, 3), (0.9, 0), (0.9, 2.5)):
        with pytest.raises(ValueError):
            student_t_quantile(probability, df)


def test_t_interval_of_one_two_three_by_hand() -> None:
    t = 0.95 / math.sqrt(2 * 0.975 * 0.025)  # t(0.975, 2), closed form
    mean, low, high = student_t_interval([1.0, 2.0, 3.0], level=0.95)
    assert mean == 2.0 and (low, high) == pytest.approx((2.0 - t / math.sqrt(3), 2.0 + t / math.sqrt(3)), rel=1e-12)


def test_mean_ci_is_the_t_interval_at_half_the_miss_rate() -> None:
    assert t_level(0.95) == 0.975 and t_level(0.9) == pytest.approx(0.95)
    _mean, low, high = mean_ci([1.0, 2.0, 3.0])
    assert (low, high) == pytest.approx(t_by_hand([1.0, 2.0, 3.0], T_9875_2), rel=1e-12)
    assert np.array_equal(np.array([low, high]), np.array(student_t_interval([1.0, 2.0, 3.0], level=0.975)[1:]))


def test_mean_ci_per_column_ignores_nan_and_collapses_on_one_seed() -> None:
    table = np.array([[1.0, 5.0, np.nan], [2.0, np.nan, np.nan], [3.0, np.nan, np.nan]])
    mean, low, high = mean_ci(table)
    assert (low[0], high[0]) == pytest.approx(t_by_hand([1.0, 2.0, 3.0], T_9875_2), rel=1e-12)
    assert mean[1] == low[1] == high[1] == 5.0  # one finite seed: the point itself
    assert np.isnan([mean[2], low[2], high[2]]).all()
    assert mean_ci([3.5, 3.5, 3.5]) == (3.5, 3.5, 3.5)  # every seed equal: zero width


def test_mean_ci_rejects_bad_input() -> None:
    with pytest.raises(ValueError, match="at least one seed"):
        mean_ci([])
    with pytest.raises(ValueError, match="strictly between 0 and 1"):
        mean_ci([1.0, 2.0], confidence=1.0)


def test_score_runs_groups_by_env_and_label_with_seed_means_and_intervals() -> None:
    runs = [
        make_run("sharing_v0", "Empathic DQN (β=0.5)", 1, [0.0] * 9 + [2.0], eval_survival=[4.0], method="empathic_dqn"),
        make_run("sharing_v0", "Empathic DQN (β=0.5)", 0, [0.0] * 9 + [6.0], eval_survival=[8.0], method="empathic_dqn"),
        make_run("sharing_v0", "Empathic DQN (β=0.5)", 2, [0.0] * 9 + [1.0], eval_survival=[0.0], method="empathic_dqn"),
        make_run("coexistence_v0", "DQN", 0, [5.0, 9.0], eval_survival=[1.0, 2.0]),
    ]
    scores = score_runs(runs)
    assert [(s.env, s.phase, s.metric) for s in scores[:2]] == [
        ("coexistence_v0", "eval", "survival"),
        ("coexistence_v0", "eval", "harms"),
    ]
    by_key = {(s.env, s.phase, s.metric): s for s in scores}
    single = by_key[("coexistence_v0", "train_final10", "survival")]
    assert (single.mean, single.ci_low, single.ci_high, single.n_seeds) == (9.0, 9.0, 9.0, 1)
    shared = by_key[("sharing_v0", "train_final10", "return")]
    assert shared.method == "empathic_dqn" and shared.n_seeds == 3 and shared.mean == 3.0
    low, high = t_by_hand([6.0, 2.0, 1.0], T_9875_2)  # the t interval at 97.5 % nominal, for a 95 % claim,
    assert low < 0 and (shared.ci_low, shared.ci_high) == pytest.approx((0.0, high), rel=1e-12)  # kept ≥ 0
    evaluated = by_key[("sharing_v0", "eval", "survival")]
    assert evaluated.mean == 4.0
    assert len(scores) == 2 * 2 * len(METRIC_NAMES)


def test_group_runs_orders_envs_then_methods_then_labels() -> None:
    runs = [
        make_run("sharing_v0", "B", 0, [1.0]),
        make_run("coexistence_v0", "Z", 0, [1.0], method="a_method"),
        make_run("coexistence_v0", "A", 0, [1.0], method="z_method"),
    ]
    assert list(group_runs(runs)) == [("coexistence_v0", "Z"), ("coexistence_v0", "A"), ("sharing_v0", "B")]


def test_rolling_curve_means_the_last_window_episodes_at_each_point() -> None:
    ends, values = [5, 10, 11, 20, 35], [1.0, 2.0, 3.0, float("nan"), 5.0]
    curve = rolling_curve(ends, values, np.array([4.0, 10.0, 15.0, 30.0, 40.0]), window=2)
    assert np.isnan(curve[0])  # no episode has ended yet
    assert curve[1:].tolist() == [1.5, 2.5, 3.0, 5.0]  # (1, 2), (2, 3), (3, nan), (nan, 5)
    assert rolling_curve(ends, values, np.array([40.0]), window=100).tolist() == [2.75]
    assert np.isnan(rolling_curve([], [], np.array([10.0]), window=1)).all()
    with pytest.raises(ValueError, match="at least 1"):
        rolling_curve(ends, values, np.array([10.0]), window=0)


def test_learning_curves_have_no_gaps_at_a_small_budget() -> None:
    """A run with fewer episodes than points: every point after the first episode has a value."""
    run = make_run("coexistence_v0", "DQN", 0, [3.0, 5.0, 9.0], end_steps=[400, 2_000, 2_100], steps=3_000)
    (curve,) = learning_curves([run], "survival", n_points=30)
    assert np.isnan(curve.mean[curve.steps < 400]).all() and np.isfinite(curve.mean[curve.steps >= 400]).all()
    assert curve.mean[-1] == 9.0  # the last tenth of three episodes: the last one


def test_learning_curves_average_seeds_per_point_with_t_intervals() -> None:
    runs = [
        make_run("coexistence_v0", "DQN", seed, values, end_steps=[25, 50, 75, 100])
        for seed, values in enumerate([[1.0, 2.0, 3.0, 4.0], [3.0, 4.0, 5.0, 6.0], [5.0, 0.0, 7.0, 8.0]])
    ]
    runs.append(make_run("sharing_v0", "DQN", 0, [1.0]))
    (curve,) = learning_curves(runs, "survival", env="coexistence_v0", n_points=4)
    assert curve.steps.tolist() == [25.0, 50.0, 75.0, 100.0]
    assert curve.mean.tolist() == [3.0, 2.0, 5.0, 6.0] and curve.n_seeds == 3
    low, high = t_by_hand([2.0, 4.0, 0.0], T_9875_2)
    assert low < 0 and (curve.ci_low[1], curve.ci_high[1]) == pytest.approx((0.0, high), rel=1e-12)  # survival ≥ 0
    assert len(learning_curves(runs, "survival", n_points=4)) == 2


def write_runs(directory: Path, runs: list[dict[str, Any]]) -> None:
    directory.mkdir(parents=True, exist_ok=True)
    for run in runs:
        (directory / f"{run['run_id']}.json").write_text(json.dumps(run), encoding="utf-8")


def test_load_results_reads_runs_subdirectory_and_ignores_temp_files(tmp_path: Path) -> None:
    documents = [make_document("coexistence_v0", "DQN", s, [1.0]) for s in (1, 0, 2)]
    write_runs(tmp_path / "runs", documents[:2])
    (tmp_path / "runs" / f".{documents[2]['run_id']}.json.abc.tmp").write_text("{half", encoding="utf-8")
    (tmp_path / "runs" / ".hidden.json").write_text("{half", encoding="utf-8")
    assert [p.name for p in result_files(tmp_path)] == [f"{documents[1]['run_id']}.json", f"{documents[0]['run_id']}.json"]
    assert [r.seed for r in load_results(tmp_path)] == [0, 1]


def test_load_results_names_a_corrupted_file(tmp_path: Path) -> None:
    write_runs(tmp_path, [make_document("coexistence_v0", "DQN", 0, [1.0])])
    (tmp_path / "broken.json").write_text('{"schema": 1, "run', encoding="utf-8")
    with pytest.raises(ValueError, match=r"broken\.json is corrupted"):
        load_results(tmp_path)


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"schema": 4}, "schemas 1, 2 and 3, got 4"),
        ({"env": None, "steps": None}, None),
        ({"seed": "0"}, "field seed: expected an int"),
    ],
)
def test_load_results_rejects_malformed_files(tmp_path: Path, change: dict[str, Any], message: str | None) -> None:
    run = make_document("coexistence_v0", "DQN", 0, [1.0])
    run.update(change)
    for key in [key for key, value in change.items() if value is None]:
        del run[key]
    write_runs(tmp_path, [run])
    with pytest.raises(ValueError, match=message or "field env: missing"):
        load_results(tmp_path)


def test_load_results_rejects_ragged_columns_and_duplicate_runs(tmp_path: Path) -> None:
    run = make_document("coexistence_v0", "DQN", 0, [1.0, 0.0])
    run["train"]["harms"] = [0.0]
    write_runs(tmp_path / "a", [run])
    with pytest.raises(ValueError, match="different lengths"):
        load_results(tmp_path / "a")
    duplicate = make_document("coexistence_v0", "DQN", 0, [1.0])
    write_runs(tmp_path / "b", [duplicate])
    (tmp_path / "b" / "copy.json").write_text(json.dumps(duplicate))  # one run, two files
    with pytest.raises(ValueError, match="same run"):
        load_results(tmp_path / "b")
    other = {**duplicate, "config": {**duplicate["config"], "env_kwargs": {"max_cycles": 400}}}  # another experiment, one label
    write_runs(tmp_path / "c", [duplicate, derive_run_id(other)])
    with pytest.raises(ValueError, match=r"same label 'DQN'.*two experiments"):
        load_results(tmp_path / "c")


def test_result_files_rejects_a_missing_directory(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="does not exist"):
        result_files(tmp_path / "nowhere")
