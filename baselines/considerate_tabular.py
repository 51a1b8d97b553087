"""Be Considerate's exact optimum on the tabular model of an environment whose robot is never
harmed (the charger task), read off its engine by :func:`empathy_zoo.exact_solver.tabular_model`.

The rule is :mod:`baselines.considerate_exact`'s, on the model's joint states instead of
Coexistence's displacements. The robot's reward is the model's, plus Be Considerate's bonus
``γ·α·V_other(s')`` at the time limit. The robot does not see the clock, so the time limit is a
chance ``h`` per step (``time_limit_rate``, by default ``1 / max_cycles``) that the step is the
episode's last. The bonus is paid where the other is still there at the step's end; none once it
has left. ``V_other`` is the other's own value, from the other's own rewards (the model's
``other_reward``), under the robot's ε-greedy policy, the other's episode ending when it is
harmed. The robot's optimum depends on ``V_other`` and ``V_other`` on the robot's policy: the two
are iterated to a fixed point from ``V_other = 1/(1 − γ)``; a ``RuntimeError`` says when the
greedy policy keeps flipping instead. Once the other is gone every method acts alike
(:func:`empathy_zoo.exact_solver.alone_policy`).
"""

from __future__ import annotations

import numpy as np

from empathy_zoo.actions import NUM_ACTIONS
from empathy_zoo.exact_solver import TabularModel, episode_steps, optimal_values
from empathy_zoo.reference import greedy_policy

__all__ = ["considerate_model_values", "other_values", "ROUNDS"]

ROUNDS = 100
"""Most rounds of the robot's optimum and the other's value before a ``RuntimeError``."""


def considerate_model_values(
    model: TabularModel,
    epsilon: float = 0.0,
    *,
    caring: float = 1.0,
    time_limit_rate: float | None = None,
    gamma: float = 0.99,
    tolerance: float = 1e-10,
) -> np.ndarray:
    """The robot's ``Q``, ``(states, 5)``, at the joint fixed point of its optimum and the other's
    value (see the module page; ``time_limit_rate`` ``None``: ``1 / max_cycles``)."""
    if model.robot_harmed.any():
        raise ValueError(f"{model.env}'s robot can be harmed: its Be Considerate optimum is baselines.considerate_exact's")
    if not 0.0 <= float(epsilon) <= 1.0:
        raise ValueError(f"epsilon must lie in [0, 1], got {epsilon!r}")
    if not float(caring) >= 0.0:
        raise ValueError(f"caring must be at least 0, got {caring!r}")
    rate = 1.0 / episode_steps(model) if time_limit_rate is None else float(time_limit_rate)
    if not 0.0 <= rate <= 1.0:
        raise ValueError(f"time_limit_rate must lie in [0, 1], got {time_limit_rate!r}")
    stays = ~model.other_harmed
    v_other = np.full(model.states, 1.0 / (1.0 - gamma))
    for _ in range(ROUNDS):
        bonus = np.where(stays, rate * gamma * caring * v_other[model.after], 0.0)
        q = optimal_values(model, gamma, tolerance, reward=model.reward + bonus)
        policy = epsilon / NUM_ACTIONS + (1.0 - epsilon) * greedy_policy(q)
        v_next = other_values(model, policy, gamma)
        if float(np.abs(v_next - v_other).max()) < tolerance:
            return q
        v_other = v_next
    raise RuntimeError(f"the robot's optimum and the other's value found no joint fixed point at caring {caring}")


def other_values(model: TabularModel, policy: np.ndarray, gamma: float = 0.99) -> np.ndarray:
    """The other's own value, ``(states,)``, under the robot's ``(states, 5)`` policy, solved
    exactly: its reward each step, its episode ending when it is harmed."""
    weight = np.broadcast_to(policy[:, :, None] / NUM_ACTIONS, model.after.shape)
    stays = ~model.other_harmed
    source = np.broadcast_to(np.arange(model.states)[:, None, None], model.after.shape)
    step = np.zeros((model.states, model.states))
    np.add.at(step, (source[stays], model.after[stays]), weight[stays])
    reward = (weight * model.other_reward).sum(axis=(1, 2))
    return np.linalg.solve(np.eye(model.states) - gamma * step, reward)
