"""The exact optimum beside the learners: per Coexistence curve of a run that learns an empathic
target the reference models (Empathic DQN's, or the silver rule's; with the in-view swap or the
omniscient one), on the environment's reward, what the fully observing optimum of the same β
(:mod:`empathy_zoo.reference`) would score at the ε the run explored with at each point of
training. Which target, β, γ and ε schedule a run has, its result file's description says
(:mod:`leaderboard.run_facts`). Drawn dashed in the curve's colour."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from leaderboard.run_facts import description_of, exploration_of, in_paper_setting

__all__ = ["REFERENCE_METRICS", "REFERENCE_ENV", "MODELLED_ARGUMENTS", "reference_curve"]

REFERENCE_METRICS = ("harms", "survival")
"""Metrics the Coexistence reference gives."""
REFERENCE_ENV = "coexistence_v0"
"""The environment the reference solves."""
MODELLED_ARGUMENTS = ("size", "view", "max_cycles")
"""Environment arguments the reference takes; every other must be at its default."""


def reference_curve(runs: Sequence[dict[str, Any]], metric: str, steps: np.ndarray) -> np.ndarray | None:
    """The reference's ``metric`` at each of ``steps`` for a group of runs, or ``None`` when the
    reference does not apply (another env, fixed agent or target, a reward transform, a
    description without β, γ or ε schedule; runs of different descriptions)."""
    from empathy_zoo.reference import RULES, coexistence_optimum

    if metric not in REFERENCE_METRICS or not runs:
        return None
    first = runs[0]
    described = description_of(first)
    if (
        first["env"] != REFERENCE_ENV
        or not in_paper_setting(first, varying=MODELLED_ARGUMENTS)
        or described["target"] not in RULES
        or described["reward"] is not None
        or any(described[name] is None for name in ("selfishness", "gamma", "exploration"))
        or any(description_of(run) != described for run in runs)
    ):
        return None
    epsilon_at = exploration_of(first)
    arguments = {
        "gamma": described["gamma"],
        "rule": described["target"],
        "in_view_only": bool(described["in_view_only"]),
        **{k: int(v) for k, v in (first.get("config", {}).get("env_kwargs") or {}).items() if k in MODELLED_ARGUMENTS},
    }
    values = []
    for step in steps:
        epsilon = round(epsilon_at(int(step)), 3)
        outcome = coexistence_optimum(described["selfishness"], epsilon, **arguments)
        values.append(getattr(outcome, metric))
    return np.asarray(values, dtype=np.float64)
