"""Be Considerate's exact optimum on the tabular model of an environment whose robot is never
harmed (the charger task), read off its engine by :func:`empathy_zoo.exact_solver.tabular_model`.

The rule is :mod:`baselines.considerate_exact`'s, on the model's joint states instead of
Coexistence's displacements. The robot's reward is the model's, plus Be Considerate's bonus
``γ·α·V_other(s')`` at the time limit. The robot does not see the clock, so the time limit is a
chance ``h`` per step (``time_limit_rate``, by default ``1 / max_cycles``) that the step is the
episode's last. The bonus is paid where the other is still there at the step's end; none once it
has left. ``V_other`` is the other's own value, from the other's own rewards (the model's
``other_reward``), under the robot's ε-greedy policy, the other's episode ending when it is
harmed or when the episode ends for both (Sharing's last battery: no bonus is paid there). The
robot's optimum depends on ``V_other`` and ``V_other`` on the robot's policy: the two are iterated
to a fixed point from ``V_other = 1/(1 − γ)``; a ``RuntimeError`` says when the greedy policy keeps
flipping instead. Once the other is gone every method acts alike
(:func:`empathy_zoo.exact_solver.alone_policy`).

Where an episode ends on its own (:attr:`empathy_zoo.exact_solver.TabularModel.ended`: Sharing's
last battery), ``1 / max_cycles`` is not the time limit's chance per step: most episodes never
reach it. :func:`considerate_ending_policy` measures it under the robot's ε-greedy policy, as the
chance that an episode reaches the time limit over its expected steps, and iterates the policy
and that chance to a fixed point from DQN's (on Sharing of size 5 the chance is 0 at ε ≤ 0.01
and 4·10⁻²⁸⁸ at ε = 0.05: Be Considerate acts as DQN, as its runs do).
"""

from __future__ import annotations

import numpy as np

from empathy_zoo.actions import NUM_ACTIONS
from empathy_zoo.exact_solver import TabularModel, alone_policy, episode_steps, optimal_values, outcome
from empathy_zoo.reference import greedy_policy

__all__ = ["considerate_model_values", "considerate_ending_policy", "time_limit_rate", "other_values", "ROUNDS", "DENSE_STATES"]

ROUNDS = 100
"""Most rounds of the robot's optimum and the other's value before a ``RuntimeError``."""
DENSE_STATES = 5_000
"""Most states whose other's value is solved as one dense linear system (above: by iteration)."""
ITERATIONS = 100_000
"""Most iterations of the other's value above :data:`DENSE_STATES` states."""


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
    stays = ~model.other_harmed & ~model.ended
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


def time_limit_rate(model: TabularModel, policy: np.ndarray, epsilon: float, gamma: float = 0.99) -> float:
    """The chance that a step is cut by the time limit, the robot acting ε-greedily on the greedy
    ``policy``: the probability that an episode reaches ``max_cycles``, over its expected steps."""
    acting = epsilon / NUM_ACTIONS + (1.0 - epsilon) * policy
    result = outcome(model, acting, episode_steps(model), alone_policy(model, epsilon, gamma))
    return result.truncated / result.survival


def considerate_ending_policy(model: TabularModel, epsilon: float = 0.0, *, gamma: float = 0.99) -> np.ndarray:
    """Be Considerate's greedy policy, ``(states, 5)``, where episodes end on their own: the time
    limit's chance per step (:func:`time_limit_rate`) and the policy iterated to a fixed point,
    from DQN's (see the module page); ``RuntimeError`` where none is found in :data:`ROUNDS` rounds."""
    policy = greedy_policy(optimal_values(model, gamma))
    for _ in range(ROUNDS):
        rate = time_limit_rate(model, policy, epsilon, gamma)
        following = greedy_policy(considerate_model_values(model, epsilon, time_limit_rate=rate, gamma=gamma))
        if np.array_equal(following, policy):
            return policy
        policy = following
    raise RuntimeError("Be Considerate's policy and the time limit's chance found no joint fixed point")


def other_values(model: TabularModel, policy: np.ndarray, gamma: float = 0.99, tolerance: float = 1e-10) -> np.ndarray:
    """The other's own value, ``(states,)``, under the robot's ``(states, 5)`` policy: its reward
    each step, its episode ending when it is harmed or ends for both. Solved exactly up to
    :data:`DENSE_STATES` states; above, by iteration until ``γ/(1−γ)·‖V_{k+1} − V_k‖∞ < tolerance``
    (a dense matrix of Sharing's 30,000 states would take 7 GB)."""
    weight = np.broadcast_to(policy[:, :, None] / model.other_moves, model.after.shape)
    stays = ~model.other_harmed & ~model.ended
    reward = (weight * model.other_reward).sum(axis=(1, 2))
    if model.states > DENSE_STATES:
        going_on = np.where(stays, weight, 0.0)
        v = np.zeros(model.states)
        for _ in range(ITERATIONS):
            v_next = reward + gamma * (going_on * v[model.after]).sum(axis=(1, 2))
            change = float(np.abs(v_next - v).max())
            v = v_next
            if gamma / (1.0 - gamma) * change < tolerance:
                return v
        raise RuntimeError(f"the other's value did not converge in {ITERATIONS:,} iterations")
    source = np.broadcast_to(np.arange(model.states)[:, None, None], model.after.shape)
    step = np.zeros((model.states, model.states))
    np.add.at(step, (source[stays], model.after[stays]), weight[stays])
    return np.linalg.solve(np.eye(model.states) - gamma * step, reward)
