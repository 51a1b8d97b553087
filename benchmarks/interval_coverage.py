"""Do the leaderboard's intervals cover what they claim? A seeded simulation under null data.

Two questions, at the seed counts the profiles use (quick 3, paper 5, and 10):

1. **The interval of a mean over seeds.** Draw ``n`` per-seed values from a distribution with a
   known mean, build each candidate 95 % interval, count how often it contains the true mean:
   the percentile bootstrap (the leaderboard before 2026-12-01), BCa, the studentized bootstrap
   (bootstrap-t) and the Student-t interval at 95 %, 97.5 % and 99 % nominal (the leaderboard now
   shows the 97.5 % one for its 95 % claim, :func:`leaderboard.aggregate.mean_ci`). Each cell is
   ``coverage % (median width / the distribution's sd)``.
2. **"Method vs DQN".** Draw both groups from the *same* distribution and count how often a
   verdict rule says ▲ or ▼ anyway (the false-positive rate per cell): today's rule (the
   stratified percentile bootstrap of the probability of improvement lies wholly above or below
   0.5), the same with Newcombe's score interval, and the exact two-sided Mann–Whitney
   permutation test at 5 % (:func:`leaderboard.improvement.permutation_test`; ties by midranks,
   exact conditional distribution, no mid-p), whose inverted interval
   (:func:`leaderboard.improvement.improvement_interval`) the leaderboard now shows. Then shift
   the method's group by 2 standard deviations and count how often each rule fires the right way
   (power), and how often each interval contains the true probability of improvement there. The
   REPRODUCTION rule "A below B" (A.high < B.low, either way round) is measured under the null
   with the percentile bootstrap and with the leaderboard's t interval.

The null distributions look like the suite's per-seed numbers: normal; skewed (lognormal σ = 0.5,
gamma k = 2); bounded and lumpy (the mean of 10 Bernoulli episodes at p = 0.3, and at p = 0.05 like
harms ≈ 0.05, where every seed is often exactly 0); survival capped at 500 steps (a point mass at
the cap); two outcomes (a greedy policy harms in every episode or in none: 0 or 1 with p = 0.4);
and the committed per-seed values themselves (every group, phase and table metric of
``docs/results/*/runs`` with at least two distinct values is a population; each replicate draws one
at random and resamples its values with replacement).

With ``--two-level``, instead: the leaderboard's own interval measured on the shipped results.
Every row of ``docs/results/{quick,methods,paper}/runs`` (two or more runs), per scored phase and
per metric the verdicts read, is a population of runs, each run a population of episodes; a
replicate draws ``n`` runs with replacement, resamples each drawn run's episodes with replacement,
averages them, and builds the t interval at 97.5 % nominal (:func:`leaderboard.aggregate.mean_ci`)
over the ``n`` run means; it covers when it contains the row's mean (of its runs' full-episode
means). Prints coverage and the share of zero-width intervals per metric, phase and ``n``, and
writes them to ``leaderboard/interval_coverage.json`` (``--json``), which the leaderboard's legends
quote (:mod:`leaderboard.measured_coverage`).

Everything comes from one ``numpy.random.default_rng(--seed)``. Prints Markdown tables, the command
and the machine.

    python benchmarks/interval_coverage.py [--replicates 2000] [--resamples 1000] [--seed 2026]
    python benchmarks/interval_coverage.py --two-level [--replicates 2000] [--seed 2026]
"""

from __future__ import annotations

import argparse
import json
import math
import shlex
import statistics
import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from machine import describe_machine  # noqa: E402  (benchmarks/machine.py, this directory is on sys.path)

from empathy_zoo.experiment.records import RunResult  # noqa: E402
from leaderboard.aggregate import (  # noqa: E402
    PHASES,
    final_episode_count,
    group_runs,
    load_results,
    longest_episode,
    mean_ci,
    run_scalars,
    student_t_interval,
    t_level,
)
from leaderboard.improvement import can_decide, improvement_interval  # noqa: E402
from leaderboard.measured_coverage import ALL_PHASES, COVERAGE_FILE  # noqa: E402
from leaderboard.tables import table_metrics  # noqa: E402

MEAN_SEEDS = (3, 5, 10)
"""Seeds per interval of a mean."""
VERDICT_SEEDS = ((3, 3), (4, 4), (5, 3), (5, 5), (10, 10))
"""(method seeds, DQN seeds) per verdict cell."""
CONFIDENCE = 0.95
"""The claimed coverage of every interval measured here."""
MEAN_CANDIDATES = ("percentile", "BCa", "bootstrap-t", "t 95 %", "t 97.5 % (leaderboard)", "t 99 %")
"""Intervals of a mean, in the table's column order."""
TWO_LEVEL_METRICS = ("harms", "survival", "batteries", "equality")
"""The metrics the leaderboard's verdicts read, whose coverage ``--two-level`` measures."""
TWO_LEVEL_DIRECTORIES = ("quick", "methods", "paper")
"""The shipped results directories (under ``docs/results``) that ``--two-level`` resamples."""
SHIFT_SDS = 2.0
"""The alternative of the power columns: the method's values shifted by this many sds."""
NORMAL = statistics.NormalDist()
Z = NORMAL.inv_cdf(0.5 + CONFIDENCE / 2)


@dataclass(frozen=True)
class Population:
    """A null data-generating distribution of per-seed values."""

    name: str
    draw: Callable[[np.random.Generator, tuple[int, ...]], np.ndarray]
    """``draw(rng, shape)``: independent per-seed values."""
    mean: float
    sd: float


def _binomial(p: float) -> Callable[[np.random.Generator, tuple[int, ...]], np.ndarray]:
    return lambda rng, shape: rng.binomial(10, p, shape) / 10.0


def parametric_populations() -> list[Population]:
    """The named null distributions (their true means and sds in closed form)."""
    lognormal_sd = math.sqrt((math.exp(0.25) - 1.0) * math.exp(0.25))
    capped_mean, capped_sd = _capped_normal_moments(430.0, 100.0, 500.0)
    return [
        Population("normal", lambda rng, shape: rng.normal(0.0, 1.0, shape), 0.0, 1.0),
        Population("lognormal σ=0.5", lambda rng, shape: rng.lognormal(0.0, 0.5, shape), math.exp(0.125), lognormal_sd),
        Population("gamma k=2", lambda rng, shape: rng.gamma(2.0, 1.0, shape), 2.0, math.sqrt(2.0)),
        Population("10 episodes, p=0.3", _binomial(0.3), 0.3, math.sqrt(0.3 * 0.7 / 10)),
        Population("10 episodes, p=0.05 (harms≈0.05)", _binomial(0.05), 0.05, math.sqrt(0.05 * 0.95 / 10)),
        Population(
            "survival capped at 500",
            lambda rng, shape: np.minimum(rng.normal(430.0, 100.0, shape), 500.0),
            capped_mean,
            capped_sd,
        ),
        Population("two outcomes 0/1, p=0.4", lambda rng, shape: rng.binomial(1, 0.4, shape).astype(float), 0.4, math.sqrt(0.24)),
    ]


def _capped_normal_moments(mu: float, sigma: float, cap: float) -> tuple[float, float]:
    """Mean and sd of ``min(N(mu, sigma²), cap)``."""
    a = (cap - mu) / sigma
    phi, big_phi = math.exp(-a * a / 2) / math.sqrt(2 * math.pi), NORMAL.cdf(a)
    # E[Z; Z < a] = -phi(a), E[Z²; Z < a] = Φ(a) - a·phi(a), with X = mu + sigma·Z below the cap
    first = mu * big_phi - sigma * phi + cap * (1 - big_phi)
    below = mu * mu * big_phi - 2 * mu * sigma * phi + sigma * sigma * (big_phi - a * phi)
    second = below + cap * cap * (1 - big_phi)
    return first, math.sqrt(second - first * first)


def committed_populations(root: Path = ROOT / "docs" / "results") -> list[np.ndarray]:
    """Per-seed values of every group, phase and table metric of the committed results (each with
    at least two distinct values)."""
    populations = []
    for directory in sorted(p for p in root.iterdir() if (p / "runs").is_dir()):
        for runs in group_runs(load_results(directory)).values():
            base = runs[0].env
            scalars = [run_scalars(run) for run in runs]
            for phase in ("eval", "train_final10"):
                for metric in table_metrics(base):
                    values = np.array([s[phase][metric] for s in scalars])
                    values = values[np.isfinite(values)]
                    if np.unique(values).size >= 2:
                        populations.append(values)
    return populations


def committed_population(values: list[np.ndarray], label: str) -> Population:
    """Each draw of a row of seeds picks one committed population at random and resamples it; the
    true mean (and sd) is that population's, so draws are returned centred on it and scaled by it."""

    def draw(rng: np.random.Generator, shape: tuple[int, ...]) -> np.ndarray:
        picks = rng.integers(0, len(values), shape[0])
        out = np.empty(shape)
        for i, k in enumerate(picks):
            pop = values[k]
            out[i] = (pop[rng.integers(0, pop.size, shape[1:])] - pop.mean()) / pop.std()
        return out

    return Population(label, draw, 0.0, 1.0)


# --- two levels: the shipped rows as populations of runs, each run a population of episodes -----


@dataclass(frozen=True)
class RowEpisodes:
    """One row's per-episode values of one phase and metric, one array per run: a population."""

    directory: str
    env: str
    label: str
    phase: str
    metric: str
    runs: tuple[np.ndarray, ...]
    """The finite per-episode values of each run (the last greedy evaluation's episodes, or the
    final 10 % of training episodes)."""
    upper: float | None
    """The bound the leaderboard cuts the interval at besides the metric's range (``max_cycles`` of
    survival), or None."""

    def mean(self) -> float:
        """The population mean: the mean over runs of their full-episode means."""
        return float(np.mean([values.mean() for values in self.runs]))


def row_episodes(results: Sequence[RunResult], directory: str, metrics: Sequence[str] = TWO_LEVEL_METRICS) -> list[RowEpisodes]:
    """Every row of ``results`` with two or more runs, per scored phase and each of ``metrics`` its
    environment's tables show, as :class:`RowEpisodes` (the episodes the leaderboard averages)."""
    rows = []
    for (env, label), runs in group_runs(results).items():
        shown = table_metrics(runs[0].env)
        for phase in PHASES:
            for metric in (m for m in metrics if m in shown):
                per_run = []
                for run in runs:
                    if phase == "eval":
                        last = run.last_eval
                        values = np.asarray(() if last is None else last.metrics[metric], dtype=np.float64)
                    else:
                        column = np.asarray(run.train.metrics[metric], dtype=np.float64)
                        values = column[column.size - final_episode_count(column.size) :]
                    values = values[np.isfinite(values)]
                    if values.size:
                        per_run.append(values)
                if len(per_run) >= 2:
                    upper = float(longest_episode(runs)) if metric == "survival" else None
                    rows.append(RowEpisodes(directory, env, label, phase, metric, tuple(per_run), upper))
    return rows


def two_level_draws(runs: Sequence[np.ndarray], n: int, replicates: int, rng: np.random.Generator) -> np.ndarray:
    """``(replicates, n)`` run means: each replicate draws ``n`` of ``runs`` with replacement, and
    each drawn run's episodes are resampled with replacement (as many as it has) and averaged."""
    picks = rng.integers(0, len(runs), (replicates, n)).ravel()
    means = np.empty(picks.size)
    for j, values in enumerate(runs):
        slots = np.flatnonzero(picks == j)
        step = max(1, 2_000_000 // values.size)
        for start in range(0, slots.size, step):
            chunk = slots[start : start + step]
            means[chunk] = values[rng.integers(0, values.size, (chunk.size, values.size))].mean(axis=1)
    return means.reshape(replicates, n)


def two_level_coverage(row: RowEpisodes, n: int, replicates: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """``(covered, zero_width)`` per replicate: whether the leaderboard's interval
    (:func:`leaderboard.aggregate.mean_ci`, the t interval at 97.5 % nominal cut to the metric's
    range) of ``n`` two-level draws (:func:`two_level_draws`) contains the row's mean (to 1e-9,
    relative: the rounding of a mean of equal values), and whether all ``n`` drawn run means were equal."""
    draws = two_level_draws(row.runs, n, replicates, rng)
    max_cycles = None if row.upper is None else int(row.upper)
    _, low, high = mean_ci(draws.T, confidence=CONFIDENCE, metrics=row.metric, max_cycles=max_cycles)
    truth = row.mean()
    tolerance = 1e-9 * max(1.0, abs(truth))
    covered = (low - tolerance <= truth) & (truth <= high + tolerance)
    return covered, np.all(draws == draws[:, :1], axis=1)


def two_level_summary(
    rows: Sequence[RowEpisodes], seeds: Sequence[int], replicates: int, rng: np.random.Generator
) -> list[dict[str, Any]]:
    """Per metric, phase (and both phases pooled, phase ``"all"``) and seed count: the coverage
    and the share of zero-width intervals, each the mean over rows of the row's share of
    ``replicates`` (rows in the order given, seed counts within each row)."""
    found: dict[tuple[str, str, int], list[tuple[float, float, str]]] = {}
    for row in rows:
        for n in seeds:
            covered, flat = two_level_coverage(row, n, replicates, rng)
            name = f"{row.directory}: {row.env} / {row.label}, {row.phase}"
            for phase in (row.phase, ALL_PHASES):
                found.setdefault((row.metric, phase, n), []).append((float(covered.mean()), float(flat.mean()), name))
    summary = []
    for (metric, phase, n), per_row in sorted(
        found.items(), key=lambda item: (_metric_order(item[0][0]), item[0][1], item[0][2])
    ):
        coverage = np.array([c for c, _, _ in per_row])
        lowest = int(np.argmin(coverage))
        summary.append(
            {
                "metric": metric,
                "phase": phase,
                "seeds": n,
                "rows": len(per_row),
                "coverage": round(float(coverage.mean()), 4),
                "zero_width": round(float(np.mean([z for _, z, _ in per_row])), 4),
                "lowest_row": per_row[lowest][2],
                "lowest_row_coverage": round(float(coverage[lowest]), 4),
            }
        )
    return summary


def _metric_order(metric: str) -> int:
    return TWO_LEVEL_METRICS.index(metric) if metric in TWO_LEVEL_METRICS else len(TWO_LEVEL_METRICS)


def write_two_level_json(path: Path, summary: list[dict[str, Any]], *, command: str, seed: int, replicates: int) -> None:
    """The figures of :func:`two_level_summary` as the leaderboard reads them
    (:func:`leaderboard.measured_coverage.read_measured_coverage`)."""
    document = {
        "command": command,
        "claimed": CONFIDENCE,
        "nominal_level": t_level(CONFIDENCE),
        "interval": "two-sided Student-t over the drawn runs' means (leaderboard.aggregate.mean_ci)",
        "resampling": "n runs of the row with replacement, then each drawn run's episodes with replacement",
        "seed": seed,
        "replicates": replicates,
        "coverage": summary,
    }
    path.write_text(json.dumps(document, indent=1, ensure_ascii=False) + "\n", encoding="utf-8")


def two_level_table(summary: list[dict[str, Any]], seeds: Sequence[int]) -> str:
    """Markdown: a row per metric and phase, a column per seed count, each cell ``coverage %
    (zero-width %)``."""
    cells: dict[tuple[str, str], dict[int, dict[str, Any]]] = {}
    for entry in summary:
        cells.setdefault((entry["metric"], entry["phase"]), {})[entry["seeds"]] = entry
    titles = {"eval": "greedy evaluation", "train_final10": "training, final 10 %", ALL_PHASES: "both"}
    rows = []
    for (metric, phase), by_n in cells.items():
        rows.append(
            [
                metric,
                titles[phase],
                str(next(iter(by_n.values()))["rows"]),
                *(f"{100 * by_n[n]['coverage']:.1f} % ({100 * by_n[n]['zero_width']:.0f} %)" if n in by_n else "" for n in seeds),
                *(f"{100 * by_n[n]['lowest_row_coverage']:.0f} %" if n in by_n else "" for n in seeds),
            ]
        )
    header = ["metric", "phase", "rows", *(f"{n} seeds" for n in seeds), *(f"lowest row, {n}" for n in seeds)]
    return markdown(header, rows)


# --- intervals of a mean: data has shape (replicates, n) --------------------------------------


def _counts(rng: np.random.Generator, replicates: int, resamples: int, n: int) -> np.ndarray:
    """How often each seed is drawn in every resample with replacement: shape (replicates, resamples, n)."""
    draws = rng.integers(0, n, (replicates * resamples, n)) + n * np.arange(replicates * resamples)[:, None]
    return np.bincount(draws.ravel(), minlength=replicates * resamples * n).reshape(replicates, resamples, n).astype(np.float64)


def percentile_bootstrap(data: np.ndarray, rng: np.random.Generator, resamples: int) -> tuple[np.ndarray, ...]:
    """Today's interval: percentiles of the resampled means. Also returns the counts and the means."""
    counts = _counts(rng, data.shape[0], resamples, data.shape[1])
    means = np.einsum("rbn,rn->rb", counts, data) / data.shape[1]
    low, high = np.quantile(means, [(1 - CONFIDENCE) / 2, (1 + CONFIDENCE) / 2], axis=1)
    return low, high, counts, means


def bca(data: np.ndarray, means: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """BCa from the bootstrap means already drawn (bias from their share below the mean,
    acceleration from the jackknife)."""
    r, n = data.shape
    theta = data.mean(axis=1)
    below = (means < theta[:, None]).mean(axis=1) + 0.5 * (means == theta[:, None]).mean(axis=1)
    jack = (data.sum(axis=1, keepdims=True) - data) / (n - 1)
    d = jack.mean(axis=1, keepdims=True) - jack
    denominator = 6.0 * (d**2).sum(axis=1) ** 1.5
    accel = np.where(denominator > 0, (d**3).sum(axis=1) / np.where(denominator > 0, denominator, 1.0), 0.0)
    low, high = np.empty(r), np.empty(r)
    sorted_means = np.sort(means, axis=1)
    b = means.shape[1]
    for i in range(r):
        if np.all(data[i] == data[i, 0]):
            low[i] = high[i] = theta[i]
            continue
        z0 = NORMAL.inv_cdf(min(max(below[i], 1.0 / b), 1 - 1.0 / b))
        bounds = []
        for z in (-Z, Z):
            q = NORMAL.cdf(z0 + (z0 + z) / (1 - accel[i] * (z0 + z)))
            bounds.append(sorted_means[i, min(b - 1, max(0, math.floor(q * b)))])
        low[i], high[i] = bounds
    return low, high


def bootstrap_t(data: np.ndarray, counts: np.ndarray, m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Studentized bootstrap from the resamples already drawn (``counts``, means ``m``): quantiles of
    (mean* − mean) / (s*/√n); a resample with s* = 0 counts as ±∞ (0 when it equals the mean), so
    with few seeds the interval is often unbounded."""
    _r, n = data.shape
    centred = data - data.mean(axis=1, keepdims=True)  # s* from the counts, centred for accuracy
    shift = m - data.mean(axis=1)[:, None]
    squares = np.einsum("rbn,rn->rb", counts, centred**2) - n * shift**2
    s = np.sqrt(np.maximum(squares, 0.0) / (n - 1))
    s = np.where(s < 1e-12 * (np.abs(data).max(axis=1, keepdims=True) + 1.0), 0.0, s)
    theta, se = data.mean(axis=1), data.std(axis=1, ddof=1) / math.sqrt(n)
    diff = m - theta[:, None]
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.where(s > 0, diff / (s / math.sqrt(n)), np.where(diff == 0, 0.0, np.sign(diff) * np.inf))
    q_low, q_high = np.quantile(t, [(1 - CONFIDENCE) / 2, (1 + CONFIDENCE) / 2], axis=1, method="inverted_cdf")
    with np.errstate(invalid="ignore"):
        low, high = theta - q_high * se, theta - q_low * se
    zero = se == 0
    return np.where(zero, theta, low), np.where(zero, theta, high)


def t_interval(data: np.ndarray, level: float) -> tuple[np.ndarray, np.ndarray]:
    """The Student-t interval at nominal ``level`` (:func:`leaderboard.aggregate.student_t_interval`,
    seeds on axis 0)."""
    _, low, high = student_t_interval(data.T, level=level)
    return low, high


def leaderboard_interval(data: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """What the leaderboard shows for a 95 % claim (:func:`leaderboard.aggregate.mean_ci`: the t
    interval at 97.5 % nominal)."""
    _, low, high = mean_ci(data.T, confidence=CONFIDENCE)
    return low, high


def mean_coverage(pop: Population, n: int, replicates: int, resamples: int, rng: np.random.Generator) -> dict[str, str]:
    chunk = max(1, 200_000 // (resamples * n))
    hits: dict[str, list[np.ndarray]] = {k: [] for k in MEAN_CANDIDATES}
    widths: dict[str, list[np.ndarray]] = {k: [] for k in hits}
    equal = []
    for start in range(0, replicates, chunk):
        data = pop.draw(rng, (min(chunk, replicates - start), n))
        equal.append(np.all(data == data[:, :1], axis=1))
        low, high, counts, means = percentile_bootstrap(data, rng, resamples)
        found = {
            "percentile": (low, high),
            "BCa": bca(data, means),
            "bootstrap-t": bootstrap_t(data, counts, means),
            "t 95 %": t_interval(data, 0.95),
            "t 97.5 % (leaderboard)": leaderboard_interval(data),
            "t 99 %": t_interval(data, 0.99),
        }
        for key, (lo, hi) in found.items():
            hits[key].append((lo <= pop.mean) & (pop.mean <= hi))
            with np.errstate(invalid="ignore"):  # an unbounded bootstrap-t interval has width ∞ (or nan: ∞ − ∞)
                widths[key].append(np.where(np.isnan(hi - lo), np.inf, hi - lo))
    row = {"all seeds equal": f"{100 * np.concatenate(equal).mean():.1f} %"}
    for key in hits:
        width = float(np.median(np.concatenate(widths[key]))) / pop.sd
        row[key] = f"{100 * np.concatenate(hits[key]).mean():.1f} % ({'∞' if math.isinf(width) else f'{width:.2f}'})"
    return row


# --- probability of improvement: x (method) against y (DQN), shape (replicates, n) / (replicates, m) --


def _probability(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """P(X > Y) + ½·P(X = Y) over the last two axes' pairs."""
    a, b = x[..., :, None], y[..., None, :]
    return (a > b).mean(axis=(-2, -1)) + 0.5 * (a == b).mean(axis=(-2, -1))


def bootstrap_probability(
    x: np.ndarray,
    y: np.ndarray,
    rng: np.random.Generator,
    resamples: int,
) -> tuple[np.ndarray, np.ndarray]:
    """Today's interval: stratified percentile bootstrap of the probability of improvement."""
    (r, n), m = x.shape, y.shape[1]
    wins = (x[:, :, None] > y[:, None, :]) + 0.5 * (x[:, :, None] == y[:, None, :])  # (r, n, m)
    cx, cy = _counts(rng, r, resamples, n), _counts(rng, r, resamples, m)
    draws = np.einsum("rbm,rbm->rb", cx @ wins, cy) / (n * m)
    low, high = np.quantile(draws, [(1 - CONFIDENCE) / 2, (1 + CONFIDENCE) / 2], axis=1)
    return low, high


def newcombe(p: np.ndarray, n: int, m: int) -> tuple[np.ndarray, np.ndarray]:
    """Score interval for P with the Hanley–McNeil variance, N* = (n + m)/2 − 1 (Newcombe 2006,
    method 5): the θ either side of p with (p − θ)² = z²·θ(1−θ)/(nm)·[1 + N*·((1−θ)/(2−θ) + θ/(1+θ))],
    by bisection."""
    star = (n + m) / 2 - 1

    def excess(theta: np.ndarray) -> np.ndarray:
        var = theta * (1 - theta) / (n * m) * (1 + star * ((1 - theta) / (2 - theta) + theta / (1 + theta)))
        return (p - theta) ** 2 - Z * Z * var

    outer, inner = np.zeros_like(p), p.copy()  # lower bound: excess(outer) ≥ 0 ≥ excess(inner)
    for _ in range(50):
        mid = 0.5 * (outer + inner)
        far = excess(mid) > 0
        outer, inner = np.where(far, mid, outer), np.where(far, inner, mid)
    low = inner
    outer, inner = np.ones_like(p), p.copy()
    for _ in range(50):
        mid = 0.5 * (outer + inner)
        far = excess(mid) > 0
        outer, inner = np.where(far, mid, outer), np.where(far, inner, mid)
    return low, inner


def true_probability(pop: Population, shift: float, rng: np.random.Generator) -> float:
    x, y = pop.draw(rng, (1, 1_000_000))[0] + shift, pop.draw(rng, (1, 1_000_000))[0]
    return float((x > y).mean() + 0.5 * (x == y).mean())


def verdict_rates(
    pop: Population,
    n: int,
    m: int,
    replicates: int,
    resamples: int,
    rng: np.random.Generator,
    committed: list[np.ndarray] | None = None,
) -> dict[str, str]:
    """False-positive rate under the null, power and interval coverage under a 2-sd shift."""
    chunk = max(1, 200_000 // (resamples * max(n, m)))
    fired: dict[str, list[np.ndarray]] = {k: [] for k in ("today", "Newcombe", "exact")}
    power: dict[str, list[np.ndarray]] = {k: [] for k in fired}
    covered: dict[str, list[np.ndarray]] = {k: [] for k in fired}
    below: dict[str, list[np.ndarray]] = {k: [] for k in ("below, percentile", "below, t 97.5 %")}
    truth_parametric = None if committed is not None else true_probability(pop, SHIFT_SDS * pop.sd, rng)
    for start in range(0, replicates, chunk):
        size = min(chunk, replicates - start)
        if committed is None:
            x, y = pop.draw(rng, (size, n)), pop.draw(rng, (size, m))
            truth = np.full(size, truth_parametric)
        else:  # both groups resampled from one committed population per replicate
            picks = rng.integers(0, len(committed), size)
            x = np.array([committed[k][rng.integers(0, committed[k].size, n)] for k in picks])
            y = np.array([committed[k][rng.integers(0, committed[k].size, m)] for k in picks])
            scale = np.array([committed[k].std() for k in picks])[:, None]
            x, y = x / scale, y / scale
            truth = np.array([_exact_shifted_probability(committed[k] / committed[k].std(), SHIFT_SDS) for k in picks])
        for shifted, record in ((0.0, fired), (SHIFT_SDS * pop.sd, power)):
            xs = x + shifted
            lo, hi = bootstrap_probability(xs, y, rng, resamples)
            p = _probability(xs, y)
            nlo, nhi = newcombe(p, n, m)
            exact = np.array([improvement_interval(a, b, confidence=CONFIDENCE) for a, b in zip(xs, y, strict=True)])
            intervals = {"today": (lo, hi), "Newcombe": (nlo, nhi), "exact": (exact[:, 1], exact[:, 2])}
            for key, (a, b) in intervals.items():
                record[key].append((a > 0.5) if shifted else ((a > 0.5) | (b < 0.5)))
                if shifted:
                    covered[key].append((a <= truth) & (truth <= b))
        xl, xh, _, _ = percentile_bootstrap(x, rng, resamples)
        yl, yh, _, _ = percentile_bootstrap(y, rng, resamples)
        below["below, percentile"].append((xh < yl) | (yh < xl))
        (xl, xh), (yl, yh) = leaderboard_interval(x), leaderboard_interval(y)
        below["below, t 97.5 %"].append((xh < yl) | (yh < xl))
    share = {key: 100 * np.concatenate(v).mean() for key, v in fired.items()}
    row = {f"FPR {key}": f"{value:.1f} %" for key, value in share.items()}
    row.update({f"power {key}": f"{100 * np.concatenate(v).mean():.0f} %" for key, v in power.items()})
    row.update({f"cover {key}": f"{100 * np.concatenate(v).mean():.0f} %" for key, v in covered.items()})
    row.update({f"FPR {key}": f"{100 * np.concatenate(v).mean():.1f} %" for key, v in below.items()})
    if not can_decide(n, m, CONFIDENCE):
        row["FPR exact"] += " (cannot fire)"
    return row


def _exact_shifted_probability(values: np.ndarray, shift: float) -> float:
    a, b = values[:, None] + shift, values[None, :]
    return float((a > b).mean() + 0.5 * (a == b).mean())


def exact_size(n: int, m: int, alpha: float = 1 - CONFIDENCE) -> float:
    """The size of the exact two-sided Mann–Whitney test for untied data: the largest achievable
    rejection probability ≤ ``alpha`` (U's null counts by the recurrence c(n, m) = c(n−1, m)·x^m + c(n, m−1))."""
    counts = {(0, j): np.array([1.0]) for j in range(m + 1)} | {(i, 0): np.array([1.0]) for i in range(n + 1)}
    for i in range(1, n + 1):
        for j in range(1, m + 1):
            a, b = np.concatenate([np.zeros(j), counts[(i - 1, j)]]), counts[(i, j - 1)]
            size = max(a.size, b.size)
            counts[(i, j)] = np.pad(a, (0, size - a.size)) + np.pad(b, (0, size - b.size))
    probability = counts[(n, m)] / counts[(n, m)].sum()
    distance = np.abs(np.arange(probability.size) - n * m / 2)
    tails = [probability[distance >= d].sum() for d in np.unique(distance)]
    return max((t for t in tails if t <= alpha + 1e-12), default=0.0)


def markdown(header: list[str], rows: list[list[str]]) -> str:
    lines = ["| " + " | ".join(header) + " |", "|" + "|".join([":---"] * 2 + ["---:"] * (len(header) - 2)) + "|"]
    return "\n".join(lines + ["| " + " | ".join(row) + " |" for row in rows])


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--replicates", type=int, default=2000, help="simulated cells per row (default 2000)")
    parser.add_argument("--resamples", type=int, default=1000, help="bootstrap resamples per interval (default 1000)")
    parser.add_argument("--seed", type=int, default=2026)
    parser.add_argument(
        "--two-level",
        action="store_true",
        help="measure the leaderboard's interval by resampling the shipped runs and their episodes (writes --json)",
    )
    parser.add_argument(
        "--json", type=Path, default=COVERAGE_FILE, help=f"where --two-level writes its figures (default {COVERAGE_FILE.name})"
    )
    parser.add_argument(
        "--seed-counts",
        default=",".join(map(str, MEAN_SEEDS)),
        help=f"with --two-level: the seed counts measured, comma-separated (default {','.join(map(str, MEAN_SEEDS))})",
    )
    args = parser.parse_args(argv)
    try:
        seed_counts = tuple(int(count) for count in args.seed_counts.split(","))
    except ValueError:
        parser.error(f"--seed-counts takes whole numbers separated by commas, got {args.seed_counts!r}")
    if any(count < 2 for count in seed_counts):
        parser.error(f"--seed-counts must each be at least 2 (an interval needs two runs), got {args.seed_counts!r}")
    if args.replicates < 1 or args.resamples < 10:
        parser.error("--replicates must be at least 1 and --resamples at least 10")
    rng = np.random.default_rng(args.seed)
    if args.two_level:
        two_level_main(args.replicates, args.seed, args.json, rng, seed_counts)
        return
    started = time.process_time()
    committed = committed_populations()
    populations = [*parametric_populations(), committed_population(committed, "committed per-seed values")]

    print("## Coverage of 95 % intervals for the mean over seeds\n")
    print(
        "Each cell: coverage (median width in sds of the distribution); 'all seeds equal': the share of "
        "draws whose seeds all gave one value, where every interval has zero width.\n"
    )
    header = ["distribution", "seeds", "all seeds equal", *MEAN_CANDIDATES]
    rows = []
    for pop in populations:
        for n in MEAN_SEEDS:
            row = mean_coverage(pop, n, args.replicates, args.resamples, rng)
            rows.append([pop.name, str(n), *(row[k] for k in header[2:])])
    print(markdown(header, rows))

    print(f"\n## Method vs DQN where nothing differs (FPR), and at a {SHIFT_SDS:g}-sd shift (power, coverage)\n")
    print(
        "FPR: share of null cells given ▲ or ▼. today: the stratified percentile bootstrap of P(improvement) "
        "excludes 0.5; Newcombe: his score interval (method 5) excludes 0.5; exact: the exact two-sided "
        "Mann–Whitney permutation test at 5 % (= its inverted interval excludes 0.5). power: share of shifted "
        "cells given ▲; cover: share of shifted cells whose interval contains the true P. below: the "
        "REPRODUCTION rule A.high < B.low either way, with each mean interval.\n"
    )
    keys = [
        "FPR today",
        "FPR Newcombe",
        "FPR exact",
        "power today",
        "power Newcombe",
        "power exact",
        "cover today",
        "cover Newcombe",
        "cover exact",
        "FPR below, percentile",
        "FPR below, t 97.5 %",
    ]
    rows = []
    for pop in populations:
        for n, m in VERDICT_SEEDS:
            row = verdict_rates(
                pop, n, m, args.replicates, args.resamples, rng, committed if pop.name.startswith("committed") else None
            )
            rows.append([pop.name, f"{n} v {m}", *(row[k] for k in keys)])
    print(markdown(["distribution", "seeds", *keys], rows))
    sizes = ", ".join(f"{n} v {m} {100 * exact_size(n, m):.1f} %" for n, m in VERDICT_SEEDS)
    print(f"\nExact size of the exact test for untied data (what its FPR estimates): {sizes}.")

    print(
        f"\n{len(committed)} committed populations; {args.replicates} replicates per row, {args.resamples} "
        f"resamples per bootstrap, seed {args.seed}; {time.process_time() - started:.0f} CPU s."
    )
    command = " ".join(shlex.quote(a) for a in ["python", "benchmarks/interval_coverage.py", *sys.argv[1:]])
    print(f"Command: `{command}`")
    for line in describe_machine():
        print(line)


def two_level_main(
    replicates: int, seed: int, json_path: Path, rng: np.random.Generator, seed_counts: Sequence[int] = MEAN_SEEDS
) -> None:
    """``--two-level``: every shipped row, phase and verdict metric as a population of runs of episodes."""
    started, wall = time.process_time(), time.perf_counter()
    rows = []
    for name in TWO_LEVEL_DIRECTORIES:
        directory = ROOT / "docs" / "results" / name / "runs"
        rows += row_episodes(load_results(directory), directory.relative_to(ROOT).as_posix())
    summary = two_level_summary(rows, seed_counts, replicates, rng)
    command = " ".join(shlex.quote(a) for a in ["python", "benchmarks/interval_coverage.py", *sys.argv[1:]])
    write_two_level_json(json_path, summary, command=command, seed=seed, replicates=replicates)
    print("## Coverage of the leaderboard's interval, resampling the shipped runs and their episodes\n")
    print(
        "Each row of docs/results/{quick,methods,paper}/runs is a population of runs, each run one of its "
        "episodes; a replicate draws n runs with replacement, resamples each drawn run's episodes, and builds "
        "the leaderboard's two-sided t interval at 97.5 % nominal over the n run means. Each cell: the share "
        "of replicates whose interval contains the row's mean, averaged over rows (in brackets: the share of "
        "zero-width intervals, all drawn runs equal); 'lowest row': the row that covered least.\n"
    )
    print(two_level_table(summary, seed_counts))
    print(
        f"\n{len(rows)} populations (row × phase × metric) with at least two runs; {replicates} replicates per "
        f"population and seed count, seed {seed}; {time.process_time() - started:.0f} CPU s, "
        f"{time.perf_counter() - wall:.0f} s wall. Figures written to {json_path}."
    )
    print(f"Command: `{command}`")
    for line in describe_machine():
        print(line)


if __name__ == "__main__":
    main()
