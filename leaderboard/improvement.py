"""How often a method does better than DQN: the probability of improvement, per metric.

For a metric and a phase, with runs ``x`` of a method and runs ``y`` of DQN (one scalar per run,
as the tables use them), the probability of improvement is ``P(X > Y) + ½·P(X = Y)`` over every
pair of runs (the Mann–Whitney statistic divided by ``n·m``, as in Agarwal et al. 2021,
"Deep RL at the edge of the statistical precipice"), where "greater" means better for the metric
(:data:`empathy_zoo.metrics.HIGHER_IS_BETTER`: fewer harms are better). 0.5 is a tie.

The exact test compares at most :data:`~empathy_zoo.limits.MAX_EXACT_TEST_SEEDS` (200) seeds, both
sides together: its null distribution takes memory ``8·n·N²`` and time ``n·N³`` for ``n`` of ``N``
seeds, so more are refused in one line (:func:`check_exact_test_seeds`) before anything is counted,
and :func:`improvements_over_dqn` checks every cell before it computes the first.

The verdict (better ▲ / worse ▼ than DQN) is the exact two-sided Mann–Whitney permutation test
at 5 % (:func:`permutation_test`): the statistic is this probability itself, its null
distribution is that of every split of the pooled runs into the two groups, ties get midranks and
the distribution is the exact one of those midranks (so its size stays at most 5 % with ties; no
mid-p). The interval shown (:func:`improvement_interval`) is the one that inverts it: the
probability ± the test's critical distance from 0.5, so ▲ / ▼ are given exactly when the interval
lies wholly above / below 0.5. With 3 runs against 3 no split is rare enough (the smallest p is
2/20 = 0.1), so no verdict can be given whatever the runs show: the cell says "too few seeds for a
verdict" (:func:`can_decide`, :func:`smallest_decidable_seeds`). The rule was chosen by a
simulation under null data like the suite's per-seed numbers (``benchmarks/interval_coverage.py``;
:data:`VERDICT_NOTE`); the percentile bootstrap used before (:func:`bootstrap_improvement`, kept
for comparison) gave a ▲ or ▼ in 19 % of 3-against-3 cells where nothing differed.

The interquartile mean (:func:`interquartile_mean`), the same paper's robust centre, is shown
beside it (with four or more seeds it trims a quarter on each side; with fewer it is the mean).

DQN is the run group whose runs are all plain DQN on the environment's reward, as their result
files' descriptions say (``dqn_reference``: method ``dqn``, or ``empathic_dqn`` at β = 1, or a
plug-in method that declares it; what the paper calls standard DQN), in the same environment
(variant) and of the same training budget (:class:`leaderboard.budgets.RunBudget`): a row is never
compared with DQN runs of another budget, and one with no DQN row of its variant and budget has no
cell. Where several DQN rows share a variant and a budget (two directories' DQN, say), a row is
compared with each of them, one cell per DQN row, none pooled; every cell names its DQN row
(:attr:`Improvement.baseline_label`).
"""

from __future__ import annotations

import functools
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from empathy_zoo.experiment.records import RunResult
from empathy_zoo.limits import MAX_EXACT_TEST_SEEDS
from empathy_zoo.metrics import HIGHER_IS_BETTER
from leaderboard.aggregate import CONFIDENCE, DEFAULT_SEED, N_RESAMPLES, PHASES, group_runs, run_scalars
from leaderboard.budgets import RunBudget, budgets_of
from leaderboard.run_facts import is_dqn_reference

__all__ = [
    "Improvement",
    "probability_of_improvement",
    "permutation_test",
    "improvement_interval",
    "can_decide",
    "check_exact_test_seeds",
    "smallest_decidable_seeds",
    "bootstrap_improvement",
    "interquartile_mean",
    "is_dqn",
    "dqn_rows",
    "row_key",
    "RowKey",
    "uncompared_rows",
    "improvements_over_dqn",
    "improvement_verdict",
    "VERDICT_MARKS",
    "TOO_FEW_SEEDS",
    "VERDICT_NOTE",
]


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
    p_value: float = math.nan
    """Two-sided p of the exact permutation test (:func:`permutation_test`); NaN when undefined."""
    baseline_label: str = ""
    """The label of the DQN row compared with (of the same variant and budget)."""

    @property
    def verdict(self) -> str:
        """``"better"`` than DQN when the whole interval lies above 0.5, ``"worse"`` when it lies
        below, :data:`TOO_FEW_SEEDS` when these seed counts cannot give a verdict at all, else
        ``"no clear difference"`` (also when it cannot be computed). The interval inverts the exact
        test, so this is the test's verdict at 5 %."""
        return improvement_verdict(self.ci_low, self.ci_high, self.n_seeds, self.n_baseline_seeds)


TOO_FEW_SEEDS = "too few seeds for a verdict"
"""The verdict of a cell whose seed counts could not reach the test's level however the runs differ."""
VERDICT_MARKS = {"better": "▲", "worse": "▼", "no clear difference": "", TOO_FEW_SEEDS: "⊘"}
"""How the tables mark a verdict."""
VERDICT_NOTE = (
    "Measured by `python benchmarks/interval_coverage.py` (BENCHMARKS.md, 2026-12-01): where nothing "
    "differs this rule gave ▲ or ▼ in 0.7–5.2 % of simulated cells at 4 to 10 seeds a side (its exact "
    "size for untied data is 2.9 % at 4 against 4, 3.2 % at 5 against 5, 4.3 % at 10 against 10), where "
    "the percentile bootstrap used before gave one in 19 % of 3-against-3 cells; where the method is 2 "
    "sds better it gave ▲ in 63–84 % of 5-against-5 cells (49 % for a 0-or-1 outcome), and its interval "
    "contained the true probability in at least 96 %."
)
"""How the verdict rule was chosen, with the false-positive rates the benchmark measured (printed
under every probability-of-improvement table)."""


def improvement_verdict(
    ci_low: float, ci_high: float, n_seeds: int | None = None, n_baseline_seeds: int | None = None, confidence: float = CONFIDENCE
) -> str:
    """The rule by which the suite says a method does better or worse than DQN in a metric: the
    interval of its probability of improvement (:func:`improvement_interval`, which inverts the
    exact permutation test) lies wholly above 0.5 (better) or below it (worse); otherwise, or when
    the interval is undefined, there is no clear difference. Given the seed counts, a cell whose
    counts cannot reach the test's level at all (:func:`can_decide`) has :data:`TOO_FEW_SEEDS`."""
    if n_seeds is not None and n_baseline_seeds is not None and not can_decide(n_seeds, n_baseline_seeds, confidence):
        return TOO_FEW_SEEDS
    if ci_low > 0.5:
        return "better"
    if ci_high < 0.5:
        return "worse"
    return "no clear difference"


def can_decide(n_seeds: int, n_baseline_seeds: int, confidence: float = CONFIDENCE) -> bool:
    """Whether ``n_seeds`` runs against ``n_baseline_seeds`` can give a verdict at all: the most
    extreme split (every run of one side beating every run of the other) has a two-sided exact
    p of ``2 / C(n + m, n)``, which must be at most ``1 − confidence``."""
    if n_seeds < 1 or n_baseline_seeds < 1:
        return False
    return 2.0 / math.comb(n_seeds + n_baseline_seeds, n_seeds) <= 1.0 - confidence + 1e-12


def smallest_decidable_seeds(confidence: float = CONFIDENCE) -> int:
    """The fewest seeds per side (the same on both) at which a verdict can be given: 4 at 95 %."""
    n = 1
    while not can_decide(n, n, confidence):
        n += 1
    return n


def check_exact_test_seeds(n_seeds: int, n_other_seeds: int) -> None:
    """Refuse (``ValueError``, one line) an exact permutation test of ``n_seeds`` against
    ``n_other_seeds`` finite runs when together they pass :data:`~empathy_zoo.limits.MAX_EXACT_TEST_SEEDS`:
    the null distribution's table would take ``8·(n_seeds + 1)·N(N + 1)`` bytes (``N`` both sides),
    swept once per seed. Called before that table is allocated."""
    total = n_seeds + n_other_seeds
    if total > MAX_EXACT_TEST_SEEDS:
        raise ValueError(
            f"the exact permutation test compares at most {MAX_EXACT_TEST_SEEDS:,} seeds, both sides together, "
            f"got {n_seeds:,} against {n_other_seeds:,} ({total:,}): its null distribution needs memory and time "
            f"that grow as seeds³ and seeds⁴; compare at most {MAX_EXACT_TEST_SEEDS:,} seeds "
            f"({MAX_EXACT_TEST_SEEDS // 2:,} a side), e.g. a results directory of fewer seeds per experiment (docs/limits.md)"
        )


def _finite_count(values: Sequence[float]) -> int:
    """How many of ``values`` are finite (the runs a test compares)."""
    return int(np.isfinite(np.asarray(values, dtype=np.float64)).sum())


def _split(x: Sequence[float], y: Sequence[float], higher_is_better: bool) -> tuple[np.ndarray, np.ndarray]:
    a = np.asarray(x, dtype=np.float64).ravel()
    b = np.asarray(y, dtype=np.float64).ravel()
    a, b = a[np.isfinite(a)], b[np.isfinite(b)]
    return (a, b) if higher_is_better else (-a, -b)


def _doubled_midranks(pooled: np.ndarray) -> np.ndarray:
    """Twice the midrank of every value of ``pooled`` (an integer: tied values share the mean rank)."""
    order = np.argsort(pooled, kind="stable")
    ranks = np.empty(pooled.size, dtype=np.int64)
    sorted_values = pooled[order]
    start = 0
    while start < pooled.size:
        stop = start
        while stop + 1 < pooled.size and sorted_values[stop + 1] == sorted_values[start]:
            stop += 1
        ranks[order[start : stop + 1]] = (start + 1) + (stop + 1)
        start = stop + 1
    return ranks


@functools.lru_cache(maxsize=512)
def _null_tails(doubled_ranks: tuple[int, ...], n: int) -> tuple[tuple[int, ...], tuple[float, ...]]:
    """The exact permutation distribution of ``D = |2W − n(N + 1)|`` (``W`` the sum of the midranks
    of ``n`` of the ``N`` pooled runs, every split equally likely): its support, ascending, and
    ``P(D ≥ d)`` at each point. Counted by dynamic programming over sums of the doubled midranks.
    ``N`` beyond :data:`~empathy_zoo.limits.MAX_EXACT_TEST_SEEDS` is refused before the table is made
    (:func:`check_exact_test_seeds`)."""
    check_exact_test_seeds(n, len(doubled_ranks) - n)
    ranks = np.asarray(doubled_ranks, dtype=np.int64)
    total = int(ranks.sum())
    counts = np.zeros((n + 1, total + 1), dtype=np.float64)
    counts[0, 0] = 1.0
    for rank in ranks:
        counts[1:, rank:] = counts[1:, rank:] + counts[:-1, : total + 1 - rank]
    by_sum = counts[n]
    sums = np.nonzero(by_sum)[0]
    centre = n * (ranks.size + 1)
    distance = np.abs(sums - centre)
    support = np.unique(distance)
    mass = np.array([by_sum[sums[distance == d]].sum() for d in support])
    tails = mass[::-1].cumsum()[::-1] / by_sum.sum()
    return tuple(int(d) for d in support), tuple(float(t) for t in tails)


def permutation_test(x: Sequence[float], y: Sequence[float], higher_is_better: bool = True) -> tuple[float, float]:
    """``(probability, p)``: the probability of improvement of ``x`` over ``y`` and the two-sided
    p of the exact Mann–Whitney permutation test (the share of splits of the pooled finite runs
    whose probability lies at least as far from 0.5; midranks for ties). NaN when a side has no
    finite run. More than :data:`~empathy_zoo.limits.MAX_EXACT_TEST_SEEDS` finite runs, both sides
    together, are refused before anything is counted (:func:`check_exact_test_seeds`)."""
    a, b = _split(x, y, higher_is_better)
    if a.size == 0 or b.size == 0:
        return math.nan, math.nan
    check_exact_test_seeds(a.size, b.size)
    ranks = _doubled_midranks(np.concatenate([a, b]))
    observed = abs(int(ranks[: a.size].sum()) - a.size * (a.size + b.size + 1))
    support, tails = _null_tails(tuple(sorted(int(r) for r in ranks)), a.size)
    probability = (int(ranks[: a.size].sum()) - a.size * (a.size + 1)) / (2.0 * a.size * b.size)
    return float(probability), tails[support.index(observed)]


def improvement_interval(
    x: Sequence[float],
    y: Sequence[float],
    higher_is_better: bool = True,
    *,
    confidence: float = CONFIDENCE,
) -> tuple[float, float, float]:
    """``(probability, low, high)``: the probability of improvement and the interval that inverts
    the exact permutation test at level ``1 − confidence``.

    The test rejects when the probability lies at least a critical distance from 0.5 (the nearest
    point of the permutation distribution whose two-sided tail is at most ``1 − confidence``); the
    interval is the probability ± ``h``, clipped to [0, 1], ``h`` halfway between that distance and
    the farthest one the test accepts, so it excludes 0.5 exactly when the test rejects. Where no
    split could be rejected (too few runs, or too many ties) ``h`` is 0.5, so the interval always
    contains 0.5. NaN when a side has no finite run. More than
    :data:`~empathy_zoo.limits.MAX_EXACT_TEST_SEEDS` finite runs, both sides together, are refused
    before anything is counted (:func:`check_exact_test_seeds`).
    """
    if not 0.0 < confidence < 1.0:
        raise ValueError(f"confidence must lie strictly between 0 and 1, got {confidence}")
    a, b = _split(x, y, higher_is_better)
    if a.size == 0 or b.size == 0:
        return math.nan, math.nan, math.nan
    check_exact_test_seeds(a.size, b.size)
    ranks = _doubled_midranks(np.concatenate([a, b]))
    support, tails = _null_tails(tuple(sorted(int(r) for r in ranks)), a.size)
    probability = (int(ranks[: a.size].sum()) - a.size * (a.size + 1)) / (2.0 * a.size * b.size)
    alpha = 1.0 - confidence + 1e-12
    accepted = [d for d, tail in zip(support, tails, strict=True) if tail > alpha]
    rejected = [d for d, tail in zip(support, tails, strict=True) if tail <= alpha]
    scale = 2.0 * a.size * b.size  # D / scale is the distance of the probability from 0.5
    half = 0.5 * (max(accepted, default=0) + min(rejected)) / scale if rejected else 0.5
    return float(probability), max(0.0, probability - half), min(1.0, probability + half)


def probability_of_improvement(
    x: Sequence[float] | np.ndarray, y: Sequence[float] | np.ndarray, higher_is_better: bool = True
) -> float:
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
    x: Sequence[float],
    y: Sequence[float],
    higher_is_better: bool = True,
    *,
    random_state: int = DEFAULT_SEED,
    n_resamples: int = N_RESAMPLES,
    confidence: float = CONFIDENCE,
) -> tuple[float, float, float]:
    """``(probability, low, high)``: the probability of improvement and its percentile-bootstrap
    interval, the runs of ``x`` and of ``y`` resampled apart (stratified). With a single run on
    either side the interval is the point itself.

    Kept for comparison (``benchmarks/interval_coverage.py``): with a handful of seeds this
    interval excludes 0.5 far more often than 5 % where nothing differs; the leaderboard uses
    :func:`improvement_interval`."""
    a = np.asarray(x, dtype=np.float64)
    b = np.asarray(y, dtype=np.float64)
    point = probability_of_improvement(a, b, higher_is_better)
    if a.size <= 1 or b.size <= 1 or math.isnan(point):
        return point, point, point
    rng = np.random.default_rng(random_state)
    draws = [
        probability_of_improvement(a[rng.integers(0, a.size, a.size)], b[rng.integers(0, b.size, b.size)], higher_is_better)
        for _ in range(n_resamples)
    ]
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
    return float(data[cut : data.size - cut].mean())


def is_dqn(run: RunResult) -> bool:
    """Whether ``run`` is standard DQN, as its description says (:func:`leaderboard.run_facts.is_dqn_reference`)."""
    return is_dqn_reference(run)


RowKey = tuple[str, tuple[RunBudget, ...], tuple[tuple[Any, ...], ...]]
"""What a row and the DQN row it is compared with share: variant, budgets and worlds (:func:`row_key`)."""


def row_key(env: str, runs: Sequence[RunResult]) -> RowKey:
    """``(variant, budgets, worlds)`` of a row of ``runs`` in the table ``env``: its runs' budgets,
    and their worlds (environment arguments and partners: a run of ``train --fixed cat_0=stay``
    keeps its variant's name, and is compared only with a DQN of its own world)."""
    worlds = {
        (
            tuple(sorted((name, repr(value)) for name, value in run.config.env_kwargs.items())),
            tuple(sorted(run.config.fixed.items())),
        )
        for run in runs
    }
    return env, budgets_of(runs), tuple(sorted(worlds))


def dqn_rows(results: Sequence[RunResult]) -> dict[RowKey, list[str]]:
    """The labels of the DQN rows (:func:`is_dqn`) per :func:`row_key` (variant, budgets and worlds
    of the row's runs), in row order (:func:`leaderboard.aggregate.group_runs`)."""
    rows: dict[RowKey, list[str]] = {}
    for (env, label), runs in group_runs(results).items():
        if all(is_dqn(run) for run in runs):
            rows.setdefault(row_key(env, runs), []).append(label)
    return rows


def uncompared_rows(results: Sequence[RunResult]) -> list[tuple[str, str]]:
    """The ``(variant, label)`` rows other than DQN's that no DQN row of their variant, budget and
    world is compared with (:func:`improvements_over_dqn` gives them no cell), in row order."""
    baselines = dqn_rows(results)
    return [
        row
        for row, runs in group_runs(results).items()
        if not all(is_dqn(run) for run in runs) and not baselines.get(row_key(row[0], runs))
    ]


def improvements_over_dqn(
    results: Sequence[RunResult],
    metrics_of: Mapping[str, Sequence[str]],
    *,
    confidence: float = CONFIDENCE,
) -> list[Improvement]:
    """Every method's probability of improving on DQN in its environment, per phase and metric
    (``metrics_of[env]``: the metrics of that env's tables), with the interval that inverts the
    exact permutation test (:func:`improvement_interval`) and the test's p; a row is compared with
    every other DQN row of its variant, budget and world (:func:`dqn_rows`), one cell each, in row order.
    A row without such a DQN row has none. The intervals draw nothing. Every cell's seeds are checked
    against :data:`~empathy_zoo.limits.MAX_EXACT_TEST_SEEDS` (:func:`check_exact_test_seeds`) before
    the first test is computed, so a refusal costs no test's time."""
    groups = group_runs(results)
    baselines = dqn_rows(results)
    scalars = {key: [run_scalars(run) for run in runs] for key, runs in groups.items()}
    compared: list[tuple[str, str, str, str, str, list[float], list[float]]] = []
    for (env, label), runs in groups.items():
        for baseline in baselines.get(row_key(env, runs), []):
            if baseline == label:
                continue
            mine, theirs = scalars[(env, label)], scalars[(env, baseline)]
            for phase in PHASES:
                for metric in metrics_of.get(env, ()):
                    x = [values[phase][metric] for values in mine]
                    y = [values[phase][metric] for values in theirs]
                    n_x, n_y = _finite_count(x), _finite_count(y)
                    if n_x and n_y:  # (a side without a finite run is no test: its cell is NaN)
                        check_exact_test_seeds(n_x, n_y)
                    compared.append((env, label, baseline, phase, metric, x, y))
    cells: list[Improvement] = []
    for env, label, baseline, phase, metric, x, y in compared:
        better = HIGHER_IS_BETTER.get(metric, True)
        p, low, high = improvement_interval(x, y, better, confidence=confidence)
        cells.append(
            Improvement(
                env,
                label,
                phase,
                metric,
                p,
                low,
                high,
                interquartile_mean(x),
                int(np.isfinite(x).sum()),
                int(np.isfinite(y).sum()),
                permutation_test(x, y, better)[1],
                baseline,
            )
        )
    return cells
