"""The exact optimum beside the learners: per Empathic DQN curve of Coexistence (and of its in-view
and silver-rule variants, each with its own target), what the fully observing optimum of the same
β (:mod:`empathy_zoo.reference`) would score at the ε the run explored with at each point of
training. Drawn dashed in the curve's colour."""

from __future__ import annotations

from collections.abc import Sequence
from types import SimpleNamespace
from typing import Any

import numpy as np

from empathy_zoo.environments import DEFAULT_POLICIES
from empathy_zoo.schedules import linear_epsilon

__all__ = ["REFERENCE_METRICS", "REFERENCE_TARGETS", "reference_curve"]

REFERENCE_METRICS = ("harms", "survival")
"""Metrics the Coexistence reference gives."""
REFERENCE_TARGETS: dict[str, dict[str, Any]] = {
    "empathic_dqn": {},
    "dqn": {},
    "empathic_dqn_in_view": {"in_view_only": True},
    "empathic_dqn_silver": {"rule": "silver"},
}
"""The methods the reference models, with the target it optimises for each (its ``rule`` /
``in_view_only`` arguments)."""


def reference_curve(runs: Sequence[dict[str, Any]], metric: str, steps: np.ndarray) -> np.ndarray | None:
    """The reference's ``metric`` at each of ``steps`` for a group of runs, or ``None`` when the
    reference does not apply (another env, fixed agent or method; runs of different settings)."""
    from empathy_zoo.reference import coexistence_optimum

    if metric not in REFERENCE_METRICS or not runs:
        return None
    first = runs[0]
    config = first.get("config", {})
    if (
        first["env"] != "coexistence_v0"
        or first["method"] not in REFERENCE_TARGETS
        or dict(config.get("fixed") or {}) != DEFAULT_POLICIES["coexistence_v0"]
        or set(config.get("env_kwargs") or {}) - {"size", "view", "max_cycles"}
        or any(run.get("config", {}).get("settings") != config.get("settings") for run in runs)
    ):
        return None
    settings = SimpleNamespace(**config["settings"])
    arguments = {
        "gamma": settings.gamma,
        **REFERENCE_TARGETS[first["method"]],
        **{k: int(v) for k, v in (config.get("env_kwargs") or {}).items()},
    }
    values = []
    for step in steps:
        epsilon = round(linear_epsilon(settings, int(step)), 3)
        outcome = coexistence_optimum(settings.selfishness, epsilon, **arguments)
        values.append(getattr(outcome, metric))
    return np.asarray(values, dtype=np.float64)
