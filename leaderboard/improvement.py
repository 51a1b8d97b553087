"""How often a method does better than DQN: the probability of improvement, per metric.

For a metric and a phase, with runs ``x`` of a method and runs ``y`` of DQN (one scalar per run,
as the tables use them), the probability of improvement is ``P(X > Y) + ½·P(X = Y)`` over every
pair of runs (the Mann–Whitney statistic divided by ``n·m``, as in Agarwal et al. 2021,
"Deep RL at the edge of the statistical precipice"), where "greater" means better for the metric
(:data:`HIGHER_IS_BETTER`: fewer harms are better). 0.5 is a tie; its interval is a percentile
bootstrap stratified by method (the runs of each method resampled apart). The interquartile mean
(:func:`interquartile_mean`), the same paper's robust centre, is shown beside it (with four or
more seeds it trims a quarter on each side; with fewer it is the mean).

DQN is the run group of method ``dqn``, or of ``empathic_dqn`` at β = 1 without a reward
transform (what the paper calls standard DQN), in the same environment (variant).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from leaderboard.aggregate import CONFIDENCE, DEFAULT_SEED, N_RESAMPLES, PHASES, group_runs, run_scalars

__all__ = [
    "HIGHER_IS_BETTER", "Improvement", "probability_of_improvement", "bootstrap_improvement",
    "interquartile_mean", "is_dqn", "improvements_over_dqn", "improvement_verdict", "VERDICT_MARKS",
]

HIGHER_IS_BETTER: dict[str, bool] = {
    "survival": True, "harms": False, "batteries": True, "other_batteries": True, "equality": True,
    "return": True, "other_return": True,
}
"""Which way each metric is better."""


@dataclass(frozen=True)
class Improvement:
    """One cell: a method's probability of improving on DQN in one metric and phase."""

    env: str
    method_label: str
    phase: str
    metric: str
    probability: float
    ci_low: float
    ci_high: float
    iqm: float
    """Interquartile mean of the method's runs (the mean when fewer than 4 seeds)."""
    n_seeds: int
    n_baseline_seeds: int

    @property
    def verdict(self) -> str:
        """``"better"`` than DQN when the whole interval lies above 0.5, ``"worse"`` when it lies
        below, else ``"no clear difference"`` (also when it cannot be computed)."""
        return improvement_verdict(self.ci_low, self.ci_high)


VERDICT_MARKS = {"better": "▲", "worse": "▼", "no clear difference": ""}
"""How the tables mark a verdict."""


def improvement_verdict(ci_low: float, ci_high: float) -> str:
    """The rule by which the suite says a method does better or worse than DQN in a metric: the
    95 % interval of its probability of improvement lies wholly above 0.5 (better) or below it
    (worse); otherwise, or when the interval is undefined, there is no clear difference."""
    if ci_low > 0.5:
        return "better"
    if ci_high < 0.5:
        return "worse"
    return "no clear difference"


def probability_of_improvement(x: Sequence[float], y: Sequence[float], higher_is_better: bool = True) -> float:
    """``P(X > Y) + ½·P(X = Y)`` over all pairs of the finite values of ``x`` and ``y`` ("greater"
    meaning better); NaN when either has no finite value."""
    a = np.asarray(x, dtype=np.float64)
    b = np.asarray(y, dtype=np.float64)
    a, b = a[np.isfinite(a)], b[np.isfinite(b)]
    if a.size == 0 or b.size == 0:
        return math.nan
    if not higher_is_better:
        a, b = -a, -b
    wins = (a[:, None] > b[None, :]).sum() + 0.5 * (a[:, None] == b[None, :]).sum()
    return float(wins / (a.size * b.size))


def bootstrap_improvement(
    x: Sequence[float], y: Sequence[float], higher_is_better: bool = True, *,
    random_state: int = DEFAULT_SEED, n_resamples: int = N_RESAMPLES, confidence: float = CONFIDENCE,
) -> tuple[float, float, float]:
    """``(probability, low, high)``: the probability of improvement and its percentile-bootstrap
    interval, the runs of ``x`` and of ``y`` resampled apart (stratified). With a single run on
    either side the interval is the point itself."""
    a = np.asarray(x, dtype=np.float64)
    b = np.asarray(y, dtype=np.float64)
    point = probability_of_improvement(a, b, higher_is_better)
    if a.size <= 1 or b.size <= 1 or math.isnan(point):
        return point, point, point
    rng = np.random.default_rng(random_state)
    draws = [probability_of_improvement(a[rng.integers(0, a.size, a.size)], b[rng.integers(0, b.size, b.size)],
                                        higher_is_better) for _ in range(n_resamples)]
    tail = 100.0 * (1.0 - confidence) / 2.0
    low, high = np.nanpercentile(draws, [tail, 100.0 - tail])
    return point, float(low), float(high)


def interquartile_mean(values: Sequence[float]) -> float:
    """Mean of the finite values after dropping the lowest and highest quarter (``⌊n/4⌋`` each);
    with fewer than 4 values nothing is dropped (the mean). NaN when none is finite."""
    data = np.sort(np.asarray(values, dtype=np.float64))
    data = data[np.isfinite(data)]
    if data.size == 0:
        return math.nan
    cut = data.size // 4
    return float(data[cut: data.size - cut].mean())


def is_dqn(run: Mapping[str, Any]) -> bool:
    """Whether ``run`` is standard DQN: method ``dqn``, or Empathic DQN at β = 1 with no reward transform."""
    config = run.get("config") or {}
    if run["method"] == "dqn":
        return True
    return (run["method"] == "empathic_dqn" and (config.get("settings") or {}).get("selfishness") == 1.0
            and config.get("reward") is None)


def improvements_over_dqn(
    results: Sequence[dict[str, Any]], metrics_of: Mapping[str, Sequence[str]], *,
    random_state: int = DEFAULT_SEED, n_resamples: int = N_RESAMPLES, confidence: float = CONFIDENCE,
) -> list[Improvement]:
    """Every method's probability of improving on DQN in its environment, per phase and metric
    (``metrics_of[env]``: the metrics of that env's tables). An env without DQN runs has none."""
    groups = group_runs(results)
    baselines = {env: runs for (env, _), runs in groups.items() if all(is_dqn(run) for run in runs)}
    cells: list[Improvement] = []
    for (env, label), runs in groups.items():
        baseline = baselines.get(env)
        if baseline is None or baseline is runs:
            continue
        mine = [run_scalars(run) for run in runs]
        theirs = [run_scalars(run) for run in baseline]
        for phase in PHASES:
            for metric in metrics_of.get(env, ()):
                x = [scalars[phase][metric] for scalars in mine]
                y = [scalars[phase][metric] for scalars in theirs]
                p, low, high = bootstrap_improvement(x, y, HIGHER_IS_BETTER.get(metric, True), random_state=random_state,
                                                     n_resamples=n_resamples, confidence=confidence)
                cells.append(Improvement(env, label, phase, metric, p, low, high, interquartile_mean(x),
                                         int(np.isfinite(x).sum()), int(np.isfinite(y).sum())))
    return cells
