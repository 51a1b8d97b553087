"""Whether a constrained method meets its cost limit, as data: the final cost of its runs against
the limit ``d`` (the Lagrangian method's harms per episode, :mod:`baselines.lagrangian`).

:func:`constraint_satisfaction` takes each run's harms per training episode and per episode of its
greedy evaluation and gives, for each phase, the mean over seeds of each run's mean cost (training:
over its final 10 % of episodes, :func:`leaderboard.aggregate.final_episode_count`), the Student-t
interval of that mean across seeds as the leaderboard draws a mean's (claimed at
:data:`~leaderboard.aggregate.CONFIDENCE`, computed at :func:`~leaderboard.aggregate.t_level` of it,
and kept at or above 0: no cost is negative), and where ``d`` lies against it:
``"above"`` (the constraint is met: even the interval's upper end is below ``d``), ``"below"``
(violated: its lower end is above ``d``) or ``"inside"`` (the seeds cannot tell). A pure function
of its numbers; rendering is the page's.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np

from leaderboard.aggregate import CONFIDENCE, FINAL_FRACTION, final_episode_count, student_t_interval, t_level

__all__ = ["ConstraintCheck", "PhaseCost", "constraint_satisfaction", "limit_position"]

LimitPosition = Literal["above", "inside", "below"]


@dataclass(frozen=True)
class PhaseCost:
    """The cost of one phase (final training, or greedy evaluation) across seeds, against ``d``."""

    per_seed: tuple[float, ...]
    """Each run's mean cost per episode in the phase, in the order given."""
    mean: float
    """Their mean."""
    low: float
    """Lower end of the t interval of the mean across seeds (the mean itself with one seed)."""
    high: float
    """Upper end of that interval."""
    limit_lies: LimitPosition
    """Where ``d`` lies against ``[low, high]``: ``"above"`` (met), ``"inside"``, ``"below"`` (violated)."""


@dataclass(frozen=True)
class ConstraintCheck:
    """The final cost of a method's runs against its limit ``d``, in training and greedy."""

    cost_limit: float
    """``d``: the cost per episode the runs may cause on average."""
    seeds: int
    """How many runs (seeds) the figures are over."""
    confidence: float
    """The coverage the intervals claim (computed at :func:`~leaderboard.aggregate.t_level` of it)."""
    final_training: PhaseCost
    """Over each run's final training episodes (:attr:`ConstraintCheck.final_fraction` of them)."""
    greedy: PhaseCost
    """Over each run's greedy-evaluation episodes."""
    final_fraction: float = FINAL_FRACTION
    """The fraction of each run's training episodes, the last ones, that count."""


def limit_position(cost_limit: float, low: float, high: float) -> LimitPosition:
    """Where ``cost_limit`` lies against the interval ``[low, high]`` (its ends count as inside)."""
    if cost_limit > high:
        return "above"
    if cost_limit < low:
        return "below"
    return "inside"


def _phase(per_seed: list[float], cost_limit: float, confidence: float) -> PhaseCost:
    """One phase's costs per seed, their mean and interval, and where ``cost_limit`` lies."""
    mean, low, high = (float(x) for x in student_t_interval(np.array(per_seed), level=t_level(confidence)))
    low = max(low, 0.0)
    return PhaseCost(tuple(per_seed), mean, low, high, limit_position(cost_limit, low, high))


def constraint_satisfaction(
    training_costs: Sequence[Sequence[float]],
    greedy_costs: Sequence[Sequence[float]],
    cost_limit: float,
    *,
    final_fraction: float = FINAL_FRACTION,
    confidence: float = CONFIDENCE,
) -> ConstraintCheck:
    """The final cost of runs against ``cost_limit`` (see the module page): ``training_costs`` holds
    each run's cost (harms) of every training episode in order, ``greedy_costs`` the same runs'
    costs of their greedy-evaluation episodes (e.g. of the last evaluation). ``ValueError`` without
    runs, for runs without episodes, for a cost that is no finite number >= 0, and for lists of
    different numbers of runs."""
    if not training_costs:
        raise ValueError("the constraint's verdict needs at least one run")
    if len(greedy_costs) != len(training_costs):
        raise ValueError(f"got the training costs of {len(training_costs)} runs and the greedy costs of {len(greedy_costs)}")
    if not math.isfinite(cost_limit) or cost_limit < 0:
        raise ValueError(f"cost_limit must be a finite number >= 0, got {cost_limit!r}")
    if not 0.0 < final_fraction <= 1.0:
        raise ValueError(f"final_fraction must lie in (0, 1], got {final_fraction!r}")
    final, greedy = [], []
    for run, (train, evaluation) in enumerate(zip(training_costs, greedy_costs, strict=True)):
        for name, costs in (("training", train), ("greedy", evaluation)):
            values = np.asarray(costs, dtype=np.float64)
            if values.ndim != 1 or values.size == 0 or not np.isfinite(values).all() or (values < 0).any():
                raise ValueError(f"run {run}: its {name} costs must be one or more finite numbers >= 0 per episode")
        values = np.asarray(train, dtype=np.float64)
        final.append(float(values[len(values) - final_episode_count(len(values), final_fraction) :].mean()))
        greedy.append(float(np.mean(np.asarray(evaluation, dtype=np.float64))))
    return ConstraintCheck(
        cost_limit=float(cost_limit),
        seeds=len(final),
        confidence=confidence,
        final_training=_phase(final, cost_limit, confidence),
        greedy=_phase(greedy, cost_limit, confidence),
        final_fraction=final_fraction,
    )
