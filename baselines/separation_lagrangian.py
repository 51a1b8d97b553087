"""# The Lagrangian's dual optimum on the exact model of Coexistence

The constrained problem of :mod:`baselines.lagrangian`: most reward subject to at most ``d`` harms
per episode. For a multiplier ``λ ≥ 0`` the robot is greedy on ``Q*`` of the reward − λ per harm
(:func:`lagrangian_values`), executed ε-greedily. :func:`lagrangian_multiplier` bisects on
``log λ`` for the least λ at which the expected harms per episode are at most ``d``: 0 where DQN
meets ``d``, ``None`` where even ``λ = 10⁴`` does not.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from empathy_zoo.actions import NUM_ACTIONS
from empathy_zoo.exact_solver import TabularModel, alone_policy, optimal_values, outcome
from empathy_zoo.reference import greedy_policy

__all__ = ["LAMBDA_RANGE", "epsilon_greedy", "lagrangian_multiplier", "lagrangian_values", "lagrangian_dual", "lagrangian_note"]

LAMBDA_RANGE = (1e-12, 1e4)
"""Where the Lagrangian's multiplier is searched (λ above 0 and at most 10⁴)."""


def epsilon_greedy(greedy: np.ndarray, epsilon: float) -> np.ndarray:
    """The ε-greedy policy of a greedy one."""
    return epsilon / NUM_ACTIONS + (1.0 - epsilon) * greedy


def lagrangian_multiplier(
    harms_at: Callable[[float], float], cost_limit: float, *, low: float = LAMBDA_RANGE[0], high: float = LAMBDA_RANGE[1]
) -> float | None:
    """The least λ (to a relative 10⁻³, by bisection on ``log λ``) at which ``harms_at(λ)`` is at
    most ``cost_limit``: 0 when ``harms_at(0)`` is, ``None`` when ``harms_at(high)`` is not."""
    if harms_at(0.0) <= cost_limit:
        return 0.0
    if harms_at(high) > cost_limit:
        return None
    if harms_at(low) <= cost_limit:
        return low
    while high / low > 1.001:
        middle = math.sqrt(low * high)
        low, high = (low, middle) if harms_at(middle) <= cost_limit else (middle, high)
    return high


def lagrangian_values(model: TabularModel, multiplier: float, gamma: float, q: np.ndarray) -> np.ndarray:
    """``Q*`` of the reward − λ per harm (``Q*`` itself at λ = 0)."""
    return q if multiplier == 0.0 else optimal_values(model, gamma, reward=model.reward - multiplier * model.other_harmed)


def lagrangian_dual(model: TabularModel, epsilon: float, gamma: float, cost_limit: float, cycles: int) -> float | None:
    """The Lagrangian's λ at ε (:func:`lagrangian_multiplier`)."""
    q = optimal_values(model, gamma)
    alone = alone_policy(model, epsilon, gamma)

    def harms_at(multiplier: float) -> float:
        policy = greedy_policy(lagrangian_values(model, multiplier, gamma, q))
        return outcome(model, epsilon_greedy(policy, epsilon), cycles, alone).harms

    return lagrangian_multiplier(harms_at, cost_limit)


def lagrangian_note(multiplier: float | None, cost_limit: float) -> str:
    """What the Lagrangian's row shows at its λ."""
    if multiplier is None:
        top = f"{LAMBDA_RANGE[1]:g}"
        return (
            f"no λ ≤ {top} meets {cost_limit:g} harms per episode: Q* prices a harm as the greedy robot meets it, "
            f"not as its ε-greedy exploration does; shown at λ = {top}"
        )
    if multiplier == 0.0:
        return f"λ = 0 meets {cost_limit:g} harms per episode: DQN itself"
    return f"the least λ meeting {cost_limit:g} harms per episode, to a relative 10⁻³"
