"""# Relative reachability's reward on the exact model of Coexistence

The reward :class:`baselines.reachability.RelativeReachability` trains on, for every state, robot
action and cat action of a :class:`empathy_zoo.exact_solver.TabularModel`:

    r' = r − λ · d(s'; b'),    b' = the state the same step reaches with the robot's no-op

with ``d`` the truncated deviation of :func:`baselines.reachability.truncated_deviation` over the
exact table of :func:`baselines.reachability_table.coexistence_reachability`, and no penalty on
the step the robot is harmed, nor from a state no step ends in (both agents on one cell, unharmed:
never reached) (the transform's default, ``final_penalty = "none"``). The baseline
is the stepwise inaction baseline without rollouts: the cat moves as it did. Once the cat is gone
the no-op costs nothing, so the value of being alone stays ``1/(1 − γ)``, as the model assumes.
The reachability table is built from the paper's engine: the reward is given for those rules only.
"""

from __future__ import annotations

import math

import numpy as np

from baselines.reachability import RelativeReachability, truncated_deviation
from baselines.reachability_table import coexistence_reachability
from empathy_zoo.exact_solver import TabularModel

__all__ = ["relative_reachability_reward", "NO_OP"]

NO_OP = 4
"""The robot's no-op (the inaction baseline's action)."""
CHUNK = 64
"""States whose deviations are computed at once (memory: ``CHUNK · 25 · |S|`` floats, twice)."""


def _codes(model: TabularModel, size: int) -> np.ndarray:
    """``(states, 5, 5)`` the reachability table's code of the state each step ends in."""
    n = size * size
    robot, cat = np.divmod(model.after, model.cells)
    return np.select([model.robot_harmed, model.other_harmed], [n * n + n, n * n + robot], robot * n + cat)


def relative_reachability_reward(model: TabularModel, transform: RelativeReachability | None = None) -> np.ndarray:
    """``(states, 5, 5)`` the model's reward less ``λ·d(s'; b')`` (see the module page), for the
    transform's weight and discount (default: the registered method's)."""
    transform = RelativeReachability() if transform is None else transform
    size = math.isqrt(model.cells)
    table = coexistence_reachability(size)
    codes = _codes(model, size)
    baseline = np.broadcast_to(codes[:, NO_OP : NO_OP + 1, :], codes.shape)
    # a state no step of Coexistence ends in (both on one cell, unharmed) is never reached: no penalty from it
    known = (table.rows[codes] >= 0) & (table.rows[baseline] >= 0)
    end = size**4 + size**2
    codes, baseline = np.where(known, codes, end), np.where(known, baseline, end)
    deviation = np.zeros(codes.shape)
    for start in range(0, model.states, CHUNK):
        part = slice(start, start + CHUNK)
        after = table.reachability(codes[part], transform.discount)
        before = table.reachability(baseline[part], transform.discount)
        deviation[part] = truncated_deviation(after, before)
    return model.reward - transform.weight * np.where(model.robot_harmed | ~known, 0.0, deviation)
