"""Performance profiles and the optimality gap, as Agarwal et al. (2021) define them.

"Deep RL at the edge of the statistical precipice" (rliable) reads a benchmark through a few
statistics of normalized scores. This module computes two of them on rliable's data shape: per
method a ``runs × tasks`` array of finite normalized scores, keyed by method
(``{method: array}``). Nothing here formats text, draws, or knows the suite's metrics;
:mod:`leaderboard.profile_section` normalizes the scores and puts them on the page.

* **Run-score distribution** (:func:`run_score_distribution`): at each threshold τ, the fraction
  of all ``(run, task)`` scores strictly above τ. Plotted against τ it is a performance profile.
* **Average-score distribution** (:func:`average_score_distribution`): the fraction of tasks
  whose mean over runs lies strictly above τ.
* **Optimality gap** (:func:`optimality_gap`): ``γ − mean(min(score, γ))`` over all runs and
  tasks. It is how far the scores fall short of γ on average. A score above γ counts as γ, so
  doing better than γ on one task cannot make up for a shortfall on another. Lower is better.

Intervals are stratified percentile-bootstrap intervals (:func:`stratified_bootstrap`): each
task's runs are resampled with replacement, apart from the other tasks' runs, and the statistic is
computed on every resample. The random state is explicit (an int seed or a
``numpy.random.Generator``), so the same scores and seed give the same interval. The percentile
bootstrap covers less than it claims with few runs: the suite measured 83 % coverage for a mean at
5 seeds where it claimed 95 % (:data:`leaderboard.aggregate.MEAN_INTERVAL_NOTE`).

rliable itself is not a dependency. Its bootstrap needs ``arch`` (and with it statsmodels, scipy,
pandas, seaborn and absl-py: 24 packages, 100 MB of wheels on Python 3.11). Its resampling draws
from numpy's global random state rather than from a state it is given. The three formulas here are
a few lines each and are tested on hand-computed numbers (``tests/test_profiles.py``).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass

import numpy as np

from leaderboard.aggregate import CONFIDENCE, DEFAULT_SEED, N_RESAMPLES, RandomState

__all__ = [
    "GAMMA",
    "Interval",
    "Profile",
    "check_scores",
    "run_score_distribution",
    "average_score_distribution",
    "optimality_gap",
    "stratified_bootstrap",
    "performance_profiles",
    "optimality_gaps",
]

GAMMA = 1.0
"""The optimality gap's threshold γ on a normalized score (rliable's default): the best score possible."""


def check_scores(scores: np.ndarray | list[list[float]], what: str = "scores") -> np.ndarray:
    """``scores`` as a ``runs × tasks`` float array; ``ValueError`` unless it is 2-D, has at least
    one run and one task, and every value is finite."""
    array = np.asarray(scores, dtype=np.float64)
    if array.ndim != 2 or array.shape[0] < 1 or array.shape[1] < 1:
        raise ValueError(f"{what}: a runs × tasks array with at least one of each is needed, got shape {array.shape}")
    if not np.isfinite(array).all():
        raise ValueError(f"{what}: every score must be finite (leave out a run without one)")
    return array


def run_score_distribution(scores: np.ndarray, taus: np.ndarray) -> np.ndarray:
    """At each τ of ``taus``: the fraction of all ``(run, task)`` scores strictly above τ."""
    array = check_scores(scores)
    thresholds = np.asarray(taus, dtype=np.float64).ravel()
    return np.asarray((array.ravel()[None, :] > thresholds[:, None]).mean(axis=1), dtype=np.float64)


def average_score_distribution(scores: np.ndarray, taus: np.ndarray) -> np.ndarray:
    """At each τ of ``taus``: the fraction of tasks whose mean score over runs is strictly above τ."""
    means = check_scores(scores).mean(axis=0)
    thresholds = np.asarray(taus, dtype=np.float64).ravel()
    return np.asarray((means[None, :] > thresholds[:, None]).mean(axis=1), dtype=np.float64)


def optimality_gap(scores: np.ndarray, gamma: float = GAMMA) -> float:
    """``γ − mean(min(score, γ))`` over all runs and tasks of ``scores``."""
    return float(gamma - np.minimum(check_scores(scores), gamma).mean())


@dataclass(frozen=True)
class Interval:
    """A statistic and its stratified-bootstrap interval (arrays for a statistic of several values)."""

    point: np.ndarray
    low: np.ndarray
    high: np.ndarray


def stratified_bootstrap(
    scores: np.ndarray,
    statistic: Callable[[np.ndarray], np.ndarray | float],
    *,
    random_state: RandomState = DEFAULT_SEED,
    n_resamples: int = N_RESAMPLES,
    confidence: float = CONFIDENCE,
) -> Interval:
    """``statistic`` of ``scores`` (``runs × tasks``) and its percentile-bootstrap interval at
    ``confidence``: each resample draws, for every task on its own, as many runs as there are, with
    replacement, from that task's runs (rliable's stratified bootstrap over runs). With one run the
    interval is the point itself."""
    if not 0.0 < confidence < 1.0:
        raise ValueError(f"confidence must lie strictly between 0 and 1, got {confidence}")
    if n_resamples < 1:
        raise ValueError(f"n_resamples must be at least 1, got {n_resamples}")
    array = check_scores(scores)
    point = np.atleast_1d(np.asarray(statistic(array), dtype=np.float64))
    runs, tasks = array.shape
    if runs == 1:
        return Interval(point, point.copy(), point.copy())
    rng = np.random.default_rng(random_state)
    rows = rng.integers(0, runs, size=(n_resamples, runs, tasks))  # (each task's runs drawn on their own)
    columns = np.arange(tasks)[None, :]
    draws = np.array([np.atleast_1d(np.asarray(statistic(array[drawn, columns]), dtype=np.float64)) for drawn in rows])
    tail = 100.0 * (1.0 - confidence) / 2.0
    low, high = np.percentile(draws, [tail, 100.0 - tail], axis=0)
    return Interval(point, np.asarray(low), np.asarray(high))


@dataclass(frozen=True)
class Profile:
    """One method's performance profile: the run-score distribution at each τ, with its band."""

    taus: np.ndarray
    fraction: np.ndarray
    """Fraction of ``(run, task)`` scores above each τ."""
    low: np.ndarray
    high: np.ndarray
    runs: int


def performance_profiles(
    score_dict: Mapping[str, np.ndarray],
    taus: np.ndarray,
    *,
    random_state: RandomState = DEFAULT_SEED,
    n_resamples: int = N_RESAMPLES,
    confidence: float = CONFIDENCE,
) -> dict[str, Profile]:
    """``{method: Profile}``: the run-score distribution of every method's ``runs × tasks`` scores
    at ``taus`` with its stratified-bootstrap band (:func:`stratified_bootstrap`). Every method
    draws from a generator seeded by ``random_state`` alone, so adding a method changes no other
    method's band."""
    thresholds = np.asarray(taus, dtype=np.float64).ravel()
    profiles = {}
    for method, scores in score_dict.items():
        array = check_scores(scores, f"scores of {method}")
        interval = stratified_bootstrap(
            array,
            lambda sample: run_score_distribution(sample, thresholds),
            random_state=random_state,
            n_resamples=n_resamples,
            confidence=confidence,
        )
        profiles[method] = Profile(thresholds, interval.point, interval.low, interval.high, array.shape[0])
    return profiles


def optimality_gaps(
    score_dict: Mapping[str, np.ndarray],
    gamma: float = GAMMA,
    *,
    random_state: RandomState = DEFAULT_SEED,
    n_resamples: int = N_RESAMPLES,
    confidence: float = CONFIDENCE,
) -> dict[str, tuple[float, float, float]]:
    """``{method: (gap, low, high)}``: every method's optimality gap at ``gamma``
    (:func:`optimality_gap`) with its stratified-bootstrap interval, each method seeded by
    ``random_state`` alone."""
    gaps = {}
    for method, scores in score_dict.items():
        interval = stratified_bootstrap(
            check_scores(scores, f"scores of {method}"),
            lambda sample: optimality_gap(sample, gamma),
            random_state=random_state,
            n_resamples=n_resamples,
            confidence=confidence,
        )
        gaps[method] = (float(interval.point[0]), float(interval.low[0]), float(interval.high[0]))
    return gaps
