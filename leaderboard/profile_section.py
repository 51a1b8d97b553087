"""The leaderboard's "Performance profiles and optimality gap" section (Agarwal et al. 2021).

Both statistics need a score normalized to [0, 1], where 1 is the best score possible. A metric of
the leaderboard's tables has one only where its range is known (:func:`normalized_score`):

* ``survival`` ÷ ``max_cycles`` (a robot is operative for at most the episode's steps);
* 1 − ``harms`` ÷ the most an episode holds: one per other agent (a harmed agent leaves, so each
  is harmed at most once an episode: :data:`~empathy_zoo.metrics.RANGE_NOTES`), and in Vase its
  vase besides (:meth:`~empathy_zoo.environments.Environment.most_harms`);
* a metric with a fixed range in :data:`~empathy_zoo.metrics.METRIC_RANGES` (``equality``), scaled
  to [0, 1] and turned so that higher is better.

Batteries and returns have no upper bound, so no profile is drawn for them. Each run's score is its
mean over the episodes of its last greedy evaluation (the tables' "Final greedy evaluation"),
normalized by its own environment arguments. Each table's environment (variant) is one task: a
row's scores are its runs × 1 task (:mod:`leaderboard.profiles`' shape).

Per environment, the section holds a table of the optimality gap at γ = 1
(:data:`~leaderboard.profiles.GAMMA`) with its interval, a column per normalized metric, and a
figure of the performance profiles (:mod:`leaderboard.profile_plot`). A leaderboard whose
environments have no normalized metric has no such section.
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from empathy_zoo.environments import ENGINES, ENVIRONMENT_TABLE
from empathy_zoo.experiment.records import RunResult
from empathy_zoo.metrics import HIGHER_IS_BETTER, METRIC_RANGES, PER_OTHER_AGENT
from leaderboard.aggregate import CONFIDENCE, DEFAULT_SEED, N_RESAMPLES, group_runs, run_scalars
from leaderboard.page import Block, Figure, Heading, Paragraph, Section, Table
from leaderboard.page_markdown import markdown_text
from leaderboard.profile_plot import plot_profiles
from leaderboard.profiles import GAMMA, Profile, optimality_gaps, performance_profiles
from leaderboard.row_names import dqn_rows_of
from leaderboard.run_facts import env_argument
from leaderboard.tables import format_mean, table_metrics

__all__ = [
    "SECTION_TITLE",
    "TAUS",
    "normalization",
    "normalized_score",
    "normalized_scores",
    "profile_metrics",
    "profile_section",
]

SECTION_TITLE = "Performance profiles and optimality gap"
TAUS = np.linspace(0.0, 1.0, 201)
"""The thresholds τ each profile is computed at (steps of 0.005)."""
PHASE = "eval"
"""The phase scored: each run's last greedy evaluation."""


def normalization(metric: str, env: str | None = None) -> str | None:
    """How ``metric`` is normalized to [0, 1], 1 the best (the column's heading), in the environment
    ``env`` where given; ``None`` for a metric without a known upper bound."""
    if metric == "survival":
        return "survival ÷ max_cycles"
    if metric in PER_OTHER_AGENT and not HIGHER_IS_BETTER.get(metric, True):
        besides = ENVIRONMENT_TABLE[env].harms_besides_agents if env is not None else 0
        return f"1 − {metric} per other agent" if not besides else f"1 − {metric} ÷ (other agents + {besides})"
    low, high = METRIC_RANGES.get(metric, (0.0, None))
    if high is None or not high > low:
        return None
    return metric if HIGHER_IS_BETTER.get(metric, True) and (low, high) == (0.0, 1.0) else f"{metric}, scaled to [0, 1]"


def normalized_score(run: RunResult, metric: str, value: float) -> float:
    """``value`` of ``metric`` in ``run`` normalized as :func:`normalization` says (by the run's own
    ``max_cycles`` and the most harms an episode of its environment holds); NaN for a metric without one."""
    if normalization(metric) is None or not math.isfinite(value):
        return math.nan
    if metric == "survival":
        return value / float(env_argument(run, "max_cycles"))
    if metric in PER_OTHER_AGENT:
        count = ENGINES[run.env].count_argument
        others = int(env_argument(run, count)) if count else 1
        return 1.0 - value / max(1, ENVIRONMENT_TABLE[run.env].most_harms(others))
    low, high = METRIC_RANGES[metric]
    scaled = (value - low) / (float(high if high is not None else math.nan) - low)  # (normalization() checked high)
    return scaled if HIGHER_IS_BETTER.get(metric, True) else 1.0 - scaled


def profile_metrics(env: str, base_env: str) -> tuple[str, ...]:
    """The metrics of ``env``'s tables that have a normalized score, in table order."""
    return tuple(metric for metric in table_metrics(env, base_env) if normalization(metric) is not None)


def normalized_scores(results: Sequence[RunResult], env: str, metric: str) -> dict[str, np.ndarray]:
    """``{row label: runs × 1 array}`` of ``env``'s rows' normalized ``metric`` in the last greedy
    evaluation, in the leaderboard's row order; runs without a finite score left out, rows without
    any too."""
    scores = {}
    for (row_env, label), runs in group_runs(results).items():
        if row_env != env:
            continue
        values = [normalized_score(run, metric, run_scalars(run, (metric,))[PHASE][metric]) for run in runs]
        finite = [value for value in values if math.isfinite(value)]
        if finite:
            scores[label] = np.array(finite, dtype=np.float64)[:, None]
    return scores


def _besides_note(envs: Sequence[str]) -> str:
    """A sentence for each base environment of ``envs`` whose episode may count harms besides one
    per other agent (Vase's vase), else nothing."""
    return "".join(
        f"In {env} an episode may count {entry.harms_besides_agents} harm besides one per other agent, "
        f"so its harms are divided by the other agents + {entry.harms_besides_agents}. "
        for env, entry in ((env, ENVIRONMENT_TABLE[env]) for env in sorted(set(envs)))
        if entry.harms_besides_agents and entry.can_harm
    )


def _intro(n_resamples: int, random_state: int, confidence: float, base_envs: Sequence[str] = ()) -> str:
    return (
        "Agarwal et al. (2021, rliable) read a benchmark through performance profiles and the optimality gap. "
        "Both need a score normalized to [0, 1], where 1 is the best score possible. "
        "Three metrics have one: survival ÷ max_cycles; 1 − harms per other agent (a harmed agent leaves, so each "
        "is harmed at most once an episode); equality as it is. "
        f"{_besides_note(base_envs)}"
        "Batteries and returns have no upper bound, so they get neither. "
        "A run's score is its mean over the episodes of its last greedy evaluation, normalized. "
        "Each environment is one task, so a row's scores are one per run. "
        "The profile at τ is the fraction of a row's runs whose score is above τ. "
        f"The optimality gap is γ minus the mean over runs of min(score, γ), with γ = {GAMMA:g}. "
        "It says how far the runs fall short of the best score possible; lower is better. "
        "With one task it is 1 minus the mean normalized score. "
        f"Intervals and bands: {confidence:.0%} stratified percentile bootstrap over runs "
        f"({n_resamples:,} resamples, seed {random_state}). "
        "The percentile bootstrap covers less than it claims with few seeds: 83 % for a mean at 5 seeds "
        "(benchmarks/interval_coverage.py). "
        "= marks an interval of zero width: every run had the same score."
    )


def _gap_table(
    results: Sequence[RunResult],
    env: str,
    base: str,
    metrics: Sequence[str],
    n_resamples: int,
    random_state: int,
    confidence: float,
) -> tuple[list[str], list[list[str]], list[tuple[str, dict[str, Profile]]]]:
    """The optimality-gap table of ``env`` (a variant of the environment ``base``: header, rows) and its figure's panels."""
    gaps: dict[str, dict[str, tuple[float, float, float, int]]] = {}
    panels = []
    for metric in metrics:
        scores = normalized_scores(results, env, metric)
        found = optimality_gaps(scores, GAMMA, random_state=random_state, n_resamples=n_resamples, confidence=confidence)
        for label, (gap, low, high) in found.items():
            gaps.setdefault(label, {})[metric] = (gap, low, high, scores[label].shape[0])
        profiles = performance_profiles(scores, TAUS, random_state=random_state, n_resamples=n_resamples, confidence=confidence)
        panels.append((str(normalization(metric, base)), profiles))
    header = ["Method", "Seeds", *(str(normalization(metric, base)) for metric in metrics)]
    rows = []
    for label, cells in gaps.items():
        seeds = max(cell[3] for cell in cells.values())
        row = [label, str(seeds)]
        for metric in metrics:
            gap, low, high, n = cells.get(metric, (math.nan, math.nan, math.nan, 0))
            row.append(format_mean(gap, low, high, n, digits=3, mark_equal=True))
        rows.append(row)
    return header, rows, panels


def profile_section(
    results: Sequence[RunResult],
    out_dir: str | os.PathLike[str],
    *,
    figures_dir: str = "figures",
    random_state: int = DEFAULT_SEED,
    n_resamples: int = N_RESAMPLES,
    confidence: float = CONFIDENCE,
) -> tuple[Section | None, dict[str, Path]]:
    """The section of ``results``, and ``{"figure:<env>:profiles": path}`` of the figures written
    into ``out_dir / figures_dir`` (linked relative to ``out_dir``); ``(None, {})`` where no
    environment has a normalized metric."""
    base_env = {run.table_env: run.env for run in results}
    envs = [(env, profile_metrics(env, base_env[env])) for env in sorted(base_env)]
    envs = [(env, metrics) for env, metrics in envs if metrics]
    if not envs:
        return None, {}
    out = Path(out_dir)
    intro = _intro(n_resamples, random_state, confidence, [base_env[env] for env, _ in envs])
    blocks: list[Block] = [Paragraph(intro, note=True)]
    figures: dict[str, Path] = {}
    dqn = dqn_rows_of(results)
    for env, metrics in envs:
        header, rows, panels = _gap_table(results, env, base_env[env], metrics, n_resamples, random_state, confidence)
        path = plot_profiles(env, panels, out / figures_dir, {label for row_env, label in dqn if row_env == env}, confidence)
        figures[f"figure:{env}:profiles"] = path
        blocks += [
            Heading(markdown_text(env)),
            Heading(f"Optimality gap (γ = {GAMMA:g}; lower is better)", 4),
            Table(header, rows),
            Figure(f"{env}: performance profiles", path.relative_to(out).as_posix(), path.read_bytes()),
        ]
    return Section(SECTION_TITLE, blocks), figures
