"""Leaderboard computation: per-run scalars, per-method means with Student-t intervals, curves.

Pure functions over arrays, in the spirit of rliable: a *run* is one result file (one seed of one
method on one env); runs are grouped by ``(env, method_label)``; every interval of a mean **over
seeds** is, for its 95 % claim, the Student-t interval at 97.5 % nominal (:func:`mean_ci`: mean ±
t·s/√n, see :func:`t_level`), which draws nothing, so the same result files always give the same
leaderboard. It was chosen by a simulation under null distributions like the suite's per-seed
numbers (``benchmarks/interval_coverage.py``; figures in :data:`MEAN_INTERVAL_NOTE`): the
percentile bootstrap used before (:func:`bootstrap_mean_ci`, kept for comparison) covered 76 % at
3 seeds and 83 % at 5 where it claimed 95 %, and the t interval at 95 % nominal 91–92 % on skewed
data.

Two phases are scored per run (see :data:`PHASES`):

* ``train_final10`` -- mean of each metric over the final 10 % of training episodes (at least one);
* ``eval`` -- mean over the episodes of the run's last greedy evaluation.

Nothing here formats text or draws; see :mod:`leaderboard.tables` and :mod:`leaderboard.plots`.
"""

from __future__ import annotations

import functools
import math
import os
import warnings
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, TypeAlias

import numpy as np

from empathy_zoo.data_files import check_input_dir, data_files
from empathy_zoo.experiment.records import RunResult
from empathy_zoo.experiment.result_reader import read_result
from empathy_zoo.metrics import METRIC_NAMES, METRIC_RANGES
from empathy_zoo.result_file import AGENT_SUFFIXES, check_one_experiment_per_label
from empathy_zoo.result_file import SCHEMA as SCHEMA_VERSION
from leaderboard.ordering import label_order
from leaderboard.run_facts import env_argument

__all__ = [
    "SCHEMA_VERSION",
    "PHASES",
    "FINAL_FRACTION",
    "N_RESAMPLES",
    "CONFIDENCE",
    "DEFAULT_SEED",
    "N_POINTS",
    "MIN_INTERVAL_SEEDS",
    "Score",
    "Curve",
    "table_env",
    "result_files",
    "load_results",
    "load_result_files",
    "check_runs",
    "group_runs",
    "final_episode_count",
    "run_scalars",
    "student_t_quantile",
    "t_level",
    "mean_ci",
    "student_t_interval",
    "bootstrap_mean_ci",
    "score_runs",
    "longest_episode",
    "rolling_curve",
    "learning_curves",
    "MEAN_INTERVAL_NOTE",
]

PHASES: tuple[str, ...] = ("eval", "train_final10")
"""Scored phases: last greedy evaluation, and the final 10 % of training episodes."""
FINAL_FRACTION = 0.1
"""Fraction of the last training episodes averaged for ``train_final10``."""
N_RESAMPLES = 2000
"""Resamples of :func:`bootstrap_mean_ci` (the percentile bootstrap, kept for comparison; the
leaderboard's own intervals draw nothing)."""
CONFIDENCE = 0.95
"""The coverage every interval claims; the mean's t interval is computed at :func:`t_level` of it
(97.5 %) to keep that claim on skewed data, and the verdict's exact test runs at ``1 − CONFIDENCE``."""
DEFAULT_SEED = 0
"""Seed of the ``numpy.random.Generator`` of :func:`bootstrap_mean_ci` unless one is given."""
N_POINTS = 50
"""Points (equally spaced training env steps) per learning curve."""
MIN_INTERVAL_SEEDS = 3
"""The fewest seeds whose interval of the mean the leaderboard shows (tables and figures): with one
there is no spread, with two the t interval has one degree of freedom and spans about ±18
standard deviations at :func:`t_level`; 3 is the least at which ``benchmarks/interval_coverage.py``
measured its coverage. The interval is still computed (the CSV keeps it)."""

RandomState: TypeAlias = np.random.Generator | int


@dataclass(frozen=True)
class Score:
    """One cell of the leaderboard: a metric of one method on one env, in one phase."""

    env: str
    method_label: str
    method: str
    """Registry name(s) of the learning method, comma-joined if a label covers several."""
    phase: str
    metric: str
    mean: float
    ci_low: float
    ci_high: float
    n_seeds: int
    """Seeds with a finite value; with 1, the interval is the point itself."""


MEAN_INTERVAL_NOTE = (
    "Measured by `python benchmarks/interval_coverage.py` (BENCHMARKS.md, 2026-12-01): on simulated "
    "per-seed numbers (normal, skewed, capped at 500 steps, or means of 10 episodes) it covered the true "
    "mean in 94–98 % of draws at 3, 5 and 10 seeds, where the percentile bootstrap used before covered "
    "76 % at 3 seeds and 83 % at 5 (normal data). It has zero width when every seed gave the same value, "
    "which does not mean the seeds cannot differ: where that is common it covers less (harms ≈ 0.05 per "
    "episode: 76 % at 3 seeds, 92 % at 5; resampling the committed per-seed values: 84 % and 89 %). "
    "An interval is cut to the metric's range (no harms below 0, no equality above 1, no survival above max_cycles)."
)
"""How the leaderboard's interval of the mean was chosen, with the coverage the benchmark measured
(printed in every legend that shows these intervals)."""


@dataclass(frozen=True)
class Curve:
    """A learning curve of one metric for one method: per-point mean over seeds and its interval."""

    env: str
    method_label: str
    metric: str
    steps: np.ndarray
    """Training env steps of every point."""
    mean: np.ndarray
    ci_low: np.ndarray
    ci_high: np.ndarray
    n_seeds: int


def result_files(results_dir: str | os.PathLike[str]) -> list[Path]:
    """Sorted ``*.json`` result files of ``results_dir`` (or of its ``runs/`` subdirectory).

    Names starting with ``.`` (temporary files of an atomic write in progress) are ignored. A result
    or agent file (``*.agent.pt``, ``*.agent.zip``) of that directory that is no regular file (a FIFO,
    a device, a directory, a dangling symbolic link or a loop of links) raises ``ValueError`` naming
    it (:func:`empathy_zoo.data_files.data_files`): no run is left out without a word.
    """
    root = check_input_dir(results_dir, "results directory", "name the directory that holds the result files")
    if (root / "runs").is_dir():
        root = root / "runs"
    for suffix in AGENT_SUFFIXES:
        data_files(root, f"*{suffix}", "agent file")
    return data_files(root, "*.json", "result file")


def table_env(result: RunResult) -> str:
    """The env name a run is tabled under: its variant (a sweep's env key) if any, else its env."""
    return result.table_env


def load_results(results_dir: str | os.PathLike[str]) -> list[RunResult]:
    """Every result file of ``results_dir`` (see :func:`result_files`), in file-name order.

    A directory without result files raises ``ValueError``; a corrupted or malformed file raises
    ``ValueError`` naming it and the field
    (:func:`empathy_zoo.experiment.result_reader.check_result`); each run is read once, into a
    :class:`~empathy_zoo.experiment.records.RunResult`; so do two runs with the same
    ``(env, method_label, seed)``, which would otherwise be counted twice, and two experiments
    with one ``(env, method_label)``, which would be mixed in one row. Several directories are
    read into one leaderboard by :func:`leaderboard.sources.load_results_dirs`.
    """
    return [result for _, result in load_result_files(results_dir)]


def load_result_files(results_dir: str | os.PathLike[str]) -> list[tuple[Path, RunResult]]:
    """``(path, result)`` of every result file of ``results_dir``, read and checked as
    :func:`load_results` reads them."""
    paths = result_files(results_dir)
    if not paths:
        raise ValueError(f"no result files (*.json) in {results_dir}: run a sweep first")
    read = [(path, read_result(path, named=False)) for path in paths]
    check_runs(read)
    return read


def check_runs(runs: Sequence[tuple[str | os.PathLike[str], RunResult]]) -> None:
    """``ValueError`` when two of ``runs`` (``(where it is, result)``) are one row's runs from two
    experiments (:func:`empathy_zoo.result_file.check_one_experiment_per_label`) or are the same
    run, ``(env, method_label, seed)``, which would be counted twice, or when one variant (a table)
    holds runs of two environments, whose rows and DQN would be read as one environment's."""
    check_one_experiment_per_label((result.table_env, result.method_label, result.run_id, str(where)) for where, result in runs)
    environment: dict[str, tuple[str, str]] = {}
    for where, result in runs:
        first_env, first = environment.setdefault(result.table_env, (result.env, str(where)))
        if first_env != result.env:
            raise ValueError(
                f"{first} and {where} are both of variant {result.table_env!r} but of two environments "
                f"({first_env}, {result.env}): a variant is one environment's table; rename one variant"
            )
    seen: dict[tuple[str, str, int], str] = {}
    for where, result in runs:
        key = (result.table_env, result.method_label, result.seed)
        if key in seen:
            raise ValueError(f"{seen[key]} and {where} are the same run {key}; move one away")
        seen[key] = str(where)


def group_runs(results: Iterable[RunResult]) -> dict[tuple[str, str], list[RunResult]]:
    """Runs grouped by ``(env, method_label)``; groups sorted by env, method, label (its numbers by
    value: :func:`leaderboard.ordering.label_order`, so α = 0.3 comes before α = 1); runs by seed."""
    groups: dict[tuple[str, str], list[RunResult]] = {}
    for result in results:
        groups.setdefault((result.table_env, result.method_label), []).append(result)

    def order(key: tuple[str, str]) -> tuple[str, str, Any]:
        return key[0], min(run.method for run in groups[key]), label_order(key[1])

    return {key: sorted(groups[key], key=lambda run: run.seed) for key in sorted(groups, key=order)}


def _method_name(runs: Sequence[RunResult]) -> str:
    return ",".join(sorted({run.method for run in runs}))


def _nanmean(values: np.ndarray, axis: int) -> np.ndarray:
    """Mean ignoring NaN along ``axis``; NaN (without a warning) where nothing is finite."""
    finite = np.isfinite(values)
    total = np.where(finite, values, 0.0).sum(axis=axis)
    count = finite.sum(axis=axis)
    return np.where(count > 0, total / np.maximum(count, 1), np.nan)


def _series(columns: Mapping[str, np.ndarray], metric: str) -> np.ndarray:
    """The column ``metric`` as float64 (empty where there is none)."""
    return np.asarray(columns.get(metric, ()), dtype=np.float64)


def final_episode_count(n_episodes: int, fraction: float = FINAL_FRACTION) -> int:
    """How many final episodes make up ``fraction`` of ``n_episodes``: ceil, at least 1 (0 if none)."""
    if n_episodes <= 0:
        return 0
    return max(1, math.ceil(round(n_episodes * fraction, 9)))


def run_scalars(
    result: RunResult, metrics: Sequence[str] = METRIC_NAMES, final_fraction: float = FINAL_FRACTION
) -> dict[str, dict[str, float]]:
    """``{phase: {metric: value}}`` for one run; NaN where the run has no such episodes."""
    last_eval = result.last_eval
    scalars: dict[str, dict[str, float]] = {"eval": {}, "train_final10": {}}
    for metric in metrics:
        column = _series(result.train.metrics, metric)
        final = column[len(column) - final_episode_count(len(column), final_fraction) :]
        scalars["train_final10"][metric] = float(_nanmean(final, axis=0))
        evaluated = _series({} if last_eval is None else last_eval.metrics, metric)
        scalars["eval"][metric] = float(_nanmean(evaluated, axis=0))
    return scalars


def bootstrap_mean_ci(
    values: np.ndarray | Sequence[float],
    *,
    random_state: RandomState = DEFAULT_SEED,
    n_resamples: int = N_RESAMPLES,
    confidence: float = CONFIDENCE,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Mean over seeds (axis 0) and its percentile-bootstrap interval: ``(mean, low, high)``.

    Kept for comparison (``benchmarks/interval_coverage.py``): with a handful of seeds this
    interval is too narrow (at 95 % nominal it covered 76 % at 3 seeds and 83 % at 5 under
    normal data); the leaderboard uses :func:`mean_ci`.

    ``values`` has shape ``(seeds,)`` or ``(seeds, k)``. Seeds are resampled with replacement,
    ``n_resamples`` times, with indices ``random_state.integers(0, seeds, (n_resamples, seeds))``
    (an int seeds a fresh ``numpy.random.default_rng``), the same indices for every column.
    NaN entries are ignored. Where at most one seed is finite, the interval is the point itself.
    """
    data = np.asarray(values, dtype=np.float64)
    if data.ndim == 0 or data.shape[0] == 0:
        raise ValueError("bootstrap_mean_ci needs at least one seed")
    rng = random_state if isinstance(random_state, np.random.Generator) else np.random.default_rng(random_state)
    mean = _nanmean(data, axis=0)
    n_finite = np.isfinite(data).sum(axis=0)
    n_seeds = data.shape[0]
    if n_seeds == 1:
        return mean, mean.copy(), mean.copy()
    indices = rng.integers(0, n_seeds, size=(n_resamples, n_seeds))
    resampled = _nanmean(data[indices], axis=1)
    tail = 100.0 * (1.0 - confidence) / 2.0
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # an all-NaN column gives NaN, as wanted
        low, high = np.nanpercentile(resampled, [tail, 100.0 - tail], axis=0)
    single = n_finite <= 1
    return mean, np.where(single, mean, low), np.where(single, mean, high)


@functools.lru_cache(maxsize=256)
def student_t_quantile(probability: float, df: int) -> float:
    """The ``probability`` quantile of Student's t with ``df`` (a positive integer) degrees of freedom.

    Inverts the exact finite series of the t distribution's CDF for integer ``df`` (Abramowitz and
    Stegun 26.7.3-4) by bisection to machine precision; ``student_t_quantile(0.975, 2)`` is
    ``0.95 / sqrt(0.04875)`` ≈ 4.3027. Bad input raises ``ValueError``.
    """
    if not 0.0 < probability < 1.0:
        raise ValueError(f"a quantile needs a probability strictly between 0 and 1, got {probability}")
    if int(df) != df or df < 1:
        raise ValueError(f"degrees of freedom must be a positive integer, got {df}")
    df = int(df)
    if probability == 0.5:
        return 0.0
    target = max(probability, 1.0 - probability)
    high = 1.0
    while _t_cdf(high, df) < target:
        high *= 2.0
    low = 0.0
    for _ in range(200):
        middle = 0.5 * (low + high)
        if middle in (low, high):
            break
        if _t_cdf(middle, df) < target:
            low = middle
        else:
            high = middle
    quantile = 0.5 * (low + high)
    return quantile if probability > 0.5 else -quantile


def _t_cdf(t: float, df: int) -> float:
    """``P(T <= t)`` for ``t >= 0`` and integer ``df``: the finite series in θ = atan(t / √df)."""
    theta = math.atan(t / math.sqrt(df))
    sin, cos2 = math.sin(theta), math.cos(theta) ** 2
    if df % 2 == 1:
        term, total = 1.0, 0.0
        if df > 1:
            total = term
            for k in range(1, (df - 1) // 2):
                term *= cos2 * (2 * k) / (2 * k + 1)
                total += term
        inside = (2.0 / math.pi) * (theta + sin * math.cos(theta) * total)
    else:
        term, total = 1.0, 1.0
        for k in range(1, df // 2):
            term *= cos2 * (2 * k - 1) / (2 * k)
            total += term
        inside = sin * total
    return 0.5 + 0.5 * inside


def t_level(confidence: float = CONFIDENCE) -> float:
    """The nominal level of the Student-t interval the leaderboard shows for a claimed
    ``confidence``: half the miss rate, ``1 − (1 − confidence) / 2`` (97.5 % for 95 %).

    At 95 % nominal the t interval covered only 91–92 % under skewed null data (lognormal σ = 0.5,
    gamma k = 2) and 90.6–93.6 % with survival capped at 500, at 3, 5 and 10 seeds; at 97.5 % nominal
    it covered at least 94 % in each (``benchmarks/interval_coverage.py``, :data:`MEAN_INTERVAL_NOTE`).
    Measured for a 95 % claim only.
    """
    if not 0.0 < confidence < 1.0:
        raise ValueError(f"confidence must lie strictly between 0 and 1, got {confidence}")
    return 1.0 - (1.0 - confidence) / 2.0


def longest_episode(runs: Iterable[RunResult]) -> int:
    """The most steps an episode of ``runs`` can last (their ``max_cycles``; the environment's default
    where a run's config does not set it): the bound of ``survival``."""
    return max(int(env_argument(run, "max_cycles")) for run in runs)


def mean_ci(
    values: np.ndarray | Sequence[float],
    *,
    confidence: float = CONFIDENCE,
    metrics: str | Sequence[str] | None = None,
    max_cycles: int | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Mean over seeds (axis 0) and the leaderboard's interval of it for a claimed ``confidence``:
    the Student-t interval at the nominal level :func:`t_level` (97.5 % for 95 %), see
    :func:`student_t_interval`; with ``metrics`` (the metric of the values, or of each column),
    the interval is kept inside the metric's range (:data:`empathy_zoo.metrics.METRIC_RANGES`:
    no harms below 0, no equality above 1; with ``max_cycles``, no survival above it), which
    never lowers its coverage."""
    mean, low, high = student_t_interval(values, level=t_level(confidence))
    if metrics is None:
        return mean, low, high
    names = [metrics] if isinstance(metrics, str) else list(metrics)
    ranges = [
        (0.0, max_cycles) if name == "survival" and max_cycles is not None else METRIC_RANGES.get(name, (None, None))
        for name in names
    ]
    floor = np.array([-np.inf if r[0] is None else r[0] for r in ranges])
    ceiling = np.array([np.inf if r[1] is None else r[1] for r in ranges])
    if isinstance(metrics, str):
        floor, ceiling = floor[0], ceiling[0]
    return mean, np.clip(low, floor, ceiling), np.clip(high, floor, ceiling)


def student_t_interval(
    values: np.ndarray | Sequence[float],
    *,
    level: float,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Mean over seeds (axis 0) and its Student-t interval at nominal ``level``: ``(mean, low, high)``.

    ``values`` has shape ``(seeds,)`` or ``(seeds, k)``; per column, with the ``n`` finite seeds,
    the interval is ``mean ± t(½ + level/2, n − 1) · s / √n`` (``s`` the standard deviation with
    ``n − 1``). NaN entries are ignored. Where at most one seed is finite, the interval is the point
    itself (NaN where none is). No seed at all raises ``ValueError``.
    """
    data = np.asarray(values, dtype=np.float64)
    if data.ndim == 0 or data.shape[0] == 0:
        raise ValueError("a mean's interval needs at least one seed")
    if not 0.0 < level < 1.0:
        raise ValueError(f"level must lie strictly between 0 and 1, got {level}")
    mean = _nanmean(data, axis=0)
    finite = np.isfinite(data)
    n_finite = finite.sum(axis=0)
    squares = np.where(finite, (data - mean) ** 2, 0.0).sum(axis=0)
    variance = squares / np.maximum(n_finite - 1, 1)
    quantiles = np.vectorize(lambda n: student_t_quantile(0.5 + level / 2.0, int(n) - 1) if n > 1 else 0.0, otypes=[float])(
        n_finite
    )
    half = quantiles * np.sqrt(variance / np.maximum(n_finite, 1))
    single = n_finite <= 1
    return mean, np.where(single, mean, mean - half), np.where(single, mean, mean + half)


def score_runs(
    results: Iterable[RunResult],
    *,
    metrics: Sequence[str] = METRIC_NAMES,
    final_fraction: float = FINAL_FRACTION,
    confidence: float = CONFIDENCE,
) -> list[Score]:
    """Every leaderboard cell, ordered by env, method (see :func:`group_runs`), phase, metric.

    Each cell's interval is the Student-t interval of :func:`mean_ci` (it draws nothing).
    """
    scores: list[Score] = []
    for (env, label), runs in group_runs(results).items():
        per_run = [run_scalars(run, metrics, final_fraction) for run in runs]
        for phase in PHASES:
            table = np.array([[scalars[phase][metric] for metric in metrics] for scalars in per_run])
            mean, low, high = mean_ci(table, confidence=confidence, metrics=metrics, max_cycles=longest_episode(runs))
            n_finite = np.isfinite(table).sum(axis=0)
            for j, metric in enumerate(metrics):
                scores.append(
                    Score(
                        env,
                        label,
                        _method_name(runs),
                        phase,
                        metric,
                        float(mean[j]),
                        float(low[j]),
                        float(high[j]),
                        int(n_finite[j]),
                    )
                )
    return scores


def rolling_curve(
    end_steps: np.ndarray | Sequence[int], values: np.ndarray | Sequence[float], points: np.ndarray, window: int
) -> np.ndarray:
    """At each of ``points`` (env steps), the mean of ``values`` over the last ``window`` episodes
    that ended at or before it (``end_steps``, ascending); NaN before the first episode ends, and
    where those episodes hold no finite value. Every point averages up to ``window`` episodes, so a
    curve has no gaps once the first episode has ended, at any budget."""
    if window < 1:
        raise ValueError(f"window must be at least 1 episode, got {window}")
    steps = np.asarray(end_steps, dtype=np.float64)
    data = np.asarray(values, dtype=np.float64)
    finite = np.isfinite(data)
    total = np.concatenate([[0.0], np.cumsum(np.where(finite, data, 0.0))])
    count = np.concatenate([[0.0], np.cumsum(finite)])
    ended = np.searchsorted(steps, np.asarray(points, dtype=np.float64), side="right")
    first = np.maximum(ended - window, 0)
    n = count[ended] - count[first]
    return np.where(n > 0, (total[ended] - total[first]) / np.maximum(n, 1.0), np.nan)


def learning_curves(
    results: Iterable[RunResult],
    metric: str,
    *,
    env: str | None = None,
    n_points: int = N_POINTS,
    window: int | None = None,
    confidence: float = CONFIDENCE,
) -> list[Curve]:
    """Training curves of ``metric`` per ``(env, method_label)`` group (only ``env`` if given).

    Each run's curve is a rolling mean (:func:`rolling_curve`) at ``n_points`` equally spaced
    steps up to the group's largest ``steps`` (so seeds share points), over the last ``window``
    training episodes; ``None`` = a tenth of the run's episodes (:func:`final_episode_count`), so a
    curve's last point is the run's final-10 % score whatever the budget. The runs' curves are
    averaged with a per-point Student-t interval (see :func:`mean_ci`; it draws nothing).
    """
    curves: list[Curve] = []
    for (group_env, label), runs in group_runs(results).items():
        if env is not None and group_env != env:
            continue
        points = np.linspace(0.0, float(max(run.steps for run in runs)), n_points + 1)[1:]
        per_run = []
        for run in runs:
            ends = run.train.episode_end_step
            size = window if window is not None else max(1, final_episode_count(len(ends)))
            per_run.append(rolling_curve(ends, _series(run.train.metrics, metric), points, size))
        mean, low, high = mean_ci(np.array(per_run), confidence=confidence, metrics=metric, max_cycles=longest_episode(runs))
        curves.append(Curve(group_env, label, metric, points, mean, low, high, len(runs)))
    return curves
