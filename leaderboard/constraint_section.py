"""The leaderboard's "Constraint satisfaction" section: each row whose runs record a price per
training episode (the Lagrangian method's λ, ``train.lambda``) against its cost limit ``d``.

For every such row (variant and label), :func:`leaderboard.constraint.constraint_satisfaction`
gives the final cost (harms per episode) in training (final 10 % of episodes) and in the last
greedy evaluation, with its interval across seeds, and where ``d`` lies against it; beside it, λ
at the end of training (mean over seeds) and whether it still rose over the final 10 % of
episodes. A leaderboard without such rows has no such section.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from empathy_zoo.experiment.records import RunResult
from leaderboard.aggregate import final_episode_count, group_runs
from leaderboard.constraint import ConstraintCheck, PhaseCost, constraint_satisfaction
from leaderboard.page import Paragraph, Section, Table

__all__ = ["SECTION_TITLE", "constraint_rows", "constraint_section"]

SECTION_TITLE = "Constraint satisfaction"
VERDICTS = {"above": "met", "inside": "undecided", "below": "violated"}
"""What the position of ``d`` against a phase's interval says of the constraint."""


def _prices(run: RunResult) -> np.ndarray:
    """The run's price after each training episode (only for a run that records it)."""
    assert run.train.price is not None
    return run.train.price


def _cost_limit(run: RunResult) -> float:
    """The ``cost_limit`` of the run's reward transform (NaN where it has none)."""
    return float((run.config.reward or {}).get("cost_limit", float("nan")))


def constraint_rows(results: Sequence[RunResult]) -> list[tuple[str, str, float, ConstraintCheck, list[float]]]:
    """``(variant, label, d, check, λ at the end of each run)`` of every row whose runs record a price."""
    rows = []
    for (env, label), runs in group_runs(results).items():
        if not all(run.train.price is not None for run in runs):
            continue
        limits = {_cost_limit(run) for run in runs}
        if len(limits) != 1 or not all(np.isfinite(list(limits))):
            continue
        (limit,) = limits
        check = constraint_satisfaction(
            [run.train.metrics["harms"].tolist() for run in runs], [run.eval[-1].metrics["harms"].tolist() for run in runs], limit
        )
        rows.append((env, label, limit, check, [float(_prices(run)[-1]) for run in runs]))
    return rows


def _rising(runs_lambda: Sequence[Sequence[float]]) -> int:
    """How many runs' λ is higher at the end than at the start of their final 10 % of episodes."""
    return sum(values[-1] > values[-final_episode_count(len(values))] for values in runs_lambda if values)


def _cell(phase: PhaseCost) -> str:
    return f"{phase.mean:.2f} [{phase.low:.2f}, {phase.high:.2f}]: {VERDICTS[phase.limit_lies]}"


def constraint_section(results: Sequence[RunResult]) -> Section | None:
    """The section of ``results``' priced rows; ``None`` where no row records a price."""
    rows = constraint_rows(results)
    if not rows:
        return None
    priced = {(env, label) for env, label, *_ in rows}
    lambdas = {key: [_prices(run).tolist() for run in runs] for key, runs in group_runs(results).items() if key in priced}
    header = ["Variant", "Method", "d", "training, final 10 %", "final greedy evaluation", "λ at the end", "λ still rising"]
    table = [
        [
            env,
            label,
            f"{limit:g}",
            _cell(check.final_training),
            _cell(check.greedy),
            f"{float(np.mean(ends)):.1f}",
            f"{_rising(lambdas[env, label])} of {len(ends)} runs",
        ]
        for env, label, limit, check, ends in rows
    ]
    intro = (
        "Harms per episode against the cost limit d of each row whose runs price their cost with a multiplier λ "
        "(the Lagrangian method): the mean over seeds [its interval across seeds, as the tables'], and whether d lies "
        "above the interval (met), inside it (undecided) or below it (violated)."
    )
    return Section(SECTION_TITLE, [Paragraph(intro, note=True), Table(header, table, text_columns=2)])  # (labels: data)
