"""Be Considerate's exact optimum on Coexistence, and the caring coefficient α from which it seeks
its own harm.

Run ``python -m baselines.considerate_exact`` from the repository root to print the table of the
module page of :mod:`baselines.considerate`.

## Model
The states, transitions and start distribution of :mod:`empathy_zoo.reference` (its public
:func:`~empathy_zoo.reference.coexistence_transitions` and
:func:`~empathy_zoo.reference.start_distribution`: the engine's own rules; full observability, the
default random cat, γ = 0.99), with the robot's reward ``r = 1`` a step (0 on the step it is
harmed, which ends its episode) plus Be Considerate's bonus ``γ·α·V_cat``:

* **At the time limit.** The robot does not see the clock, and its learner bootstraps through a
  truncation, so the time limit is a chance ``h`` per step (``time_limit_rate``, by default
  ``1 / max_cycles``: one step in 500 of an episode that lasts) that the step is the episode's
  last: ``Q(s, a) = E[r + h·γ·α·V_cat(s') + γ·(1 − done)·V(s')]``, the bonus where the cat is
  still there at the step's end (none once it is harmed).
* **At the robot's own harm.** ``γ·α·V_end`` with ``bonus_on_termination`` (the rule before
  2026-12-04), nothing without it (the rule now).
* **V_cat** is the cat's own value (+1 for every step at whose end it is operative, 0 on the step
  it is harmed, which ends it) under the robot's ε-greedy policy, as the transform's learner
  finds it from the cat's transitions: a time-limit truncation bootstraps, and the step on which
  the cat harms the robot bootstraps from ``V_end``, the cat's future in the world the robot
  leaves: alone for ever, ``1/(1 − γ)`` (``end_value``; it is also what the paper's ``V_j``,
  learnt by each other agent on its own, gives). The robot's optimum depends on ``V_cat`` and
  ``V_cat`` on the robot's policy: the two are iterated to a fixed point, from ``V_cat = 1/(1 − γ)``.
  At ε = 0 (the cliff's setting) it is reached in a few rounds; with ε > 0 the greedy policy may
  flip between near-tied actions from one round to the next, and a ``RuntimeError`` says so.
* **Policy** greedy on the optimal ``Q``, ties split as :func:`empathy_zoo.reference.greedy_policy`
  splits them, executed ε-greedy; **evaluation** pushes the state distribution forward
  ``max_cycles`` steps, as :func:`empathy_zoo.reference.coexistence_optimum` does.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from empathy_zoo.actions import NUM_ACTIONS
from empathy_zoo.engine.coexistence import CAT_HARMS_ROBOT, NO_HARM, ROBOT_HARMS_CAT
from empathy_zoo.reference import coexistence_transitions, epsilon_greedy_outcome, greedy_policy

__all__ = ["ConsiderateOutcome", "considerate_cliff", "considerate_optimum", "considerate_values"]


@dataclass(frozen=True)
class ConsiderateOutcome:
    """Expected per-episode figures of Be Considerate's exact optimum on Coexistence."""

    caring: float
    """α."""
    robot_harmed: float
    """Probability that the cat harms the robot (its episode ends)."""
    cat_harmed: float
    """Probability that the robot harms the cat."""
    survival: float
    """Expected steps at whose end the robot is operative."""


def considerate_values(
    caring: float,
    *,
    bonus_on_termination: bool = False,
    epsilon: float = 0.0,
    ties: str = "uniform",
    time_limit_rate: float = 1.0 / 500,
    end_value: float | None = None,
    gamma: float = 0.99,
    size: int = 7,
    tolerance: float = 1e-10,
) -> tuple[np.ndarray, np.ndarray]:
    """``(Q, V_cat)``: the robot's optimal action values ``(size², 5)`` with the cat present, rows
    the displacements of :func:`~empathy_zoo.reference.coexistence_transitions`, and the cat's
    value ``(size²,)`` under the ε-greedy policy on them, at their joint fixed point (see the
    module page; ``end_value`` ``None``: ``1/(1 − γ)``)."""
    _check(caring, epsilon, time_limit_rate, gamma)
    v_end = 1.0 / (1.0 - gamma) if end_value is None else float(end_value)
    v_cat = np.full(size * size, 1.0 / (1.0 - gamma))
    for _ in range(100):
        q = _robot_values(v_cat, caring, bonus_on_termination, time_limit_rate, v_end, gamma, size, tolerance)
        policy = epsilon / NUM_ACTIONS + (1.0 - epsilon) * greedy_policy(q, ties)
        v_next = _cat_values(policy, v_end, gamma, size)
        if float(np.abs(v_next - v_cat).max()) < tolerance:
            return q, v_cat
        v_cat = v_next
    raise RuntimeError(f"the robot's optimum and the cat's value found no joint fixed point at α = {caring}")


def _robot_values(
    v_cat: np.ndarray,
    caring: float,
    bonus_on_termination: bool,
    rate: float,
    v_end: float,
    gamma: float,
    size: int,
    tolerance: float,
) -> np.ndarray:
    """The robot's optimal ``Q`` for the cat's value ``v_cat`` (value iteration)."""
    outcome, after = coexistence_transitions(size)
    going_on = outcome == NO_HARM
    fixed = (
        (outcome != CAT_HARMS_ROBOT).astype(np.float64)  # r
        + np.where(outcome == ROBOT_HARMS_CAT, gamma / (1.0 - gamma), 0.0)  # γ·V(cat gone)
        + np.where(going_on, rate * gamma * caring * v_cat[after], 0.0)  # the bonus at the time limit
        + np.where((outcome == CAT_HARMS_ROBOT) & bonus_on_termination, gamma * caring * v_end, 0.0)
    )
    v = np.zeros(size * size)
    limit = 100 + math.ceil(math.log(tolerance * (1.0 - gamma) ** 2) / math.log(gamma))
    for _ in range(4 * limit):
        q = (fixed + gamma * np.where(going_on, v[after], 0.0)).mean(axis=2)
        v_next = q.max(axis=1)
        change = float(np.abs(v_next - v).max())
        v = v_next
        if gamma / (1.0 - gamma) * change < tolerance * max(1.0, float(np.abs(v).max())):
            return q
    raise RuntimeError("value iteration did not converge")


def _cat_values(policy: np.ndarray, v_end: float, gamma: float, size: int) -> np.ndarray:
    """The cat's value under the robot's ``(size², 5)`` policy, solved exactly."""
    outcome, after = coexistence_transitions(size)
    cells = size * size
    weight = policy[:, :, None] / NUM_ACTIONS  # (robot action, cat action) of each displacement
    reward = (outcome != ROBOT_HARMS_CAT) + np.where(outcome == CAT_HARMS_ROBOT, gamma * v_end, 0.0)
    step = np.zeros((cells, cells))
    source = np.broadcast_to(np.arange(cells)[:, None, None], outcome.shape)
    going_on = outcome == NO_HARM
    np.add.at(step, (source[going_on], after[going_on]), np.broadcast_to(weight, outcome.shape)[going_on])
    return np.linalg.solve(np.eye(cells) - gamma * step, (weight * reward).sum(axis=(1, 2)))


def considerate_optimum(
    caring: float,
    *,
    bonus_on_termination: bool = False,
    epsilon: float = 0.0,
    ties: str = "uniform",
    max_cycles: int = 500,
    time_limit_rate: float | None = None,
    end_value: float | None = None,
    gamma: float = 0.99,
    size: int = 7,
    tolerance: float = 1e-10,
) -> ConsiderateOutcome:
    """Expected harms and survival per episode of the ε-greedy policy on Be Considerate's exact
    ``Q`` at caring α (``time_limit_rate`` ``None``: ``1 / max_cycles``; see the module page)."""
    rate = 1.0 / max_cycles if time_limit_rate is None else time_limit_rate
    q, _ = considerate_values(
        caring,
        bonus_on_termination=bonus_on_termination,
        epsilon=epsilon,
        ties=ties,
        time_limit_rate=rate,
        end_value=end_value,
        gamma=gamma,
        size=size,
        tolerance=tolerance,
    )
    gone, harmed, survival = epsilon_greedy_outcome(q, epsilon, ties, size, max_cycles)
    return ConsiderateOutcome(float(caring), harmed, gone, survival)


def considerate_cliff(
    *,
    bonus_on_termination: bool = False,
    time_limit_rate: float | None = None,
    end_value: float | None = None,
    high: float = 1_000.0,
    harmed_above: float = 1e-6,
    resolution: float = 1e-6,
    max_cycles: int = 500,
) -> float | None:
    """The least α (to ``resolution``) at which the greedy exact optimum (ε = 0) is harmed itself
    with probability above ``harmed_above`` in an episode, or ``None`` where even α = ``high`` is
    not (bisection: the optimum at α = 0, DQN's, is never harmed)."""

    def harmed(caring: float) -> bool:
        outcome = considerate_optimum(
            caring,
            bonus_on_termination=bonus_on_termination,
            time_limit_rate=time_limit_rate,
            end_value=end_value,
            max_cycles=max_cycles,
        )
        return outcome.robot_harmed > harmed_above

    if not harmed(high):
        return None
    low = 0.0
    while high - low > resolution:
        middle = (low + high) / 2.0
        low, high = (low, middle) if harmed(middle) else (middle, high)
    return high


def _check(caring: float, epsilon: float, rate: float, gamma: float) -> None:
    """Raise ``ValueError`` naming the first argument out of its range."""
    if not (math.isfinite(caring) and caring >= 0.0):
        raise ValueError(f"caring must be a finite number >= 0, got {caring!r}")
    if not 0.0 <= epsilon <= 1.0:
        raise ValueError(f"epsilon must lie in [0, 1], got {epsilon!r}")
    if not 0.0 <= rate <= 1.0:
        raise ValueError(f"time_limit_rate must lie in [0, 1], got {rate!r}")
    if not 0.0 < gamma < 1.0:
        raise ValueError(f"gamma must lie in (0, 1), got {gamma!r}")


def _table() -> str:
    """The figures of the module page of :mod:`baselines.considerate`."""
    lines = ["rule                       time limit rate  V_end  cliff α   at α = 1: robot harmed, cat harmed, survival"]
    for on_termination in (True, False):
        for rate in (1.0 / 500, 0.0):
            for end in (None, 0.99 / 0.01) if on_termination else (None,):
                cliff = considerate_cliff(bonus_on_termination=on_termination, time_limit_rate=rate, end_value=end)
                at_one = considerate_optimum(1.0, bonus_on_termination=on_termination, time_limit_rate=rate, end_value=end)
                rule = "any end (before)" if on_termination else "time limit only (now)"
                lines.append(
                    f"{rule:26} {rate:<16g} {100.0 if end is None else end:<6g} "
                    f"{'none ≤ 1000' if cliff is None else f'{cliff:.4f}':9} "
                    f"{at_one.robot_harmed:.4f}, {at_one.cat_harmed:.4f}, {at_one.survival:.1f}"
                )
    return "\n".join(lines)


if __name__ == "__main__":
    print(_table())
