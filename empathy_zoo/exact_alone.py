"""The robot alone in the exact model (:mod:`empathy_zoo.exact_solver`): once the other has gone.

Where every step alone pays the same (Coexistence: ``+1``), being alone is one value. Elsewhere (the
charger and vase tasks) it is one state per robot cell and layer, indexed ``layer · cells + cell``,
with its own ``Q*`` by value iteration; the robot then acts by :func:`alone_policy`.
"""

from __future__ import annotations

import math
from typing import Any, Protocol

import numpy as np

from empathy_zoo.actions import NUM_ACTIONS
from empathy_zoo.exact_chance import FixedDraws
from empathy_zoo.reference import greedy_policy


class TabularModel(Protocol):
    """What this module reads of :class:`empathy_zoo.exact_solver.TabularModel` (a protocol, so
    the solver imports this module and not the other way round)."""

    @property
    def cells(self) -> int: ...

    @property
    def after(self) -> np.ndarray: ...

    @property
    def alone_reward(self) -> np.ndarray: ...

    @property
    def alone_after(self) -> np.ndarray: ...

    @property
    def alone_pay(self) -> float | None: ...

    @property
    def alone_states(self) -> int: ...


__all__ = ["alone_steps", "alone_values", "alone_policy", "gone_continuation"]

ROBOT, OTHER = 0, 1


def alone_steps(engine_class: Any, cells: int, layers: int, env_kwargs: dict[str, Any]) -> tuple[np.ndarray, np.ndarray]:
    """``(reward, after)``, each ``(layers · cells, 5)``: one step of the robot alone from every
    cell and layer with every action (the other absent), read off the engine, which may draw no
    random number there (:class:`~empathy_zoo.exact_chance.FixedDraws` counts them)."""
    alone, action = (x.ravel() for x in np.indices((layers * cells, NUM_ACTIONS)))
    layer, cell = np.divmod(alone, cells)
    engine = engine_class(len(cell), **env_kwargs)
    stand_in = FixedDraws(len(cell))
    engine.streams = stand_in
    engine.reset()
    stand_in.forget()
    engine.cells = np.stack([cell, np.zeros_like(cell)], axis=1).astype(engine.cells.dtype)
    engine.present[:, OTHER] = False
    if layers > 1:
        engine.set_tabular_layer(layer)
    events = engine.step(np.stack([action, np.full_like(action, NUM_ACTIONS - 1)], axis=1))
    if stand_in.drawn.any():
        raise ValueError(f"{engine.name}'s engine drew a random number in a step of the robot alone: the model has no draw there")
    shape = (layers * cells, NUM_ACTIONS)
    after = engine.cells[:, ROBOT] + (engine.tabular_layer() * cells if layers > 1 else 0)
    return events.rewards[:, ROBOT].astype(np.float64).reshape(shape), after.reshape(shape).astype(np.int64)


def alone_values(model: TabularModel, gamma: float = 0.99, tolerance: float = 1e-10) -> np.ndarray:
    """``Q*`` of the robot alone, ``(layers · cells, 5)``, by value iteration to the same bound as
    :func:`optimal_values`."""
    v = np.zeros(model.alone_states)
    q = model.alone_reward.copy()
    scale = max(1.0, float(np.abs(model.alone_reward).max(initial=0.0)))
    limit = 100 + math.ceil(math.log(tolerance * (1.0 - gamma) ** 2 / scale) / math.log(gamma)) if gamma > 0 else 2
    for _ in range(limit):
        q = model.alone_reward + gamma * v[model.alone_after]
        v_next = q.max(axis=1)
        change = float(np.abs(v_next - v).max())
        v = v_next
        if gamma / (1.0 - gamma) * change < tolerance:
            break
    return q


def alone_policy(model: TabularModel, epsilon: float, gamma: float = 0.99, tolerance: float = 1e-10) -> np.ndarray | None:
    """The robot's ε-greedy policy alone, ``(layers · cells, 5)``, greedy on :func:`alone_values` (every
    method's: with the other gone no penalty, bonus or other-term is left), or ``None`` where
    every step alone pays the same (:attr:`TabularModel.alone_pay`)."""
    if model.alone_pay is not None:
        return None
    return epsilon / NUM_ACTIONS + (1.0 - epsilon) * greedy_policy(alone_values(model, gamma, tolerance))


def gone_continuation(model: TabularModel, gamma: float = 0.99, tolerance: float = 1e-10) -> float | np.ndarray:
    """``γ·V*`` after a step in which the other leaves: ``γ·pay/(1 − γ)`` where every step alone pays
    the same, else the model's shape: ``γ·V*_alone`` of the robot's cell after the step."""
    pay = model.alone_pay
    if pay is not None:
        return gamma * pay / (1.0 - gamma)
    return gamma * alone_values(model, gamma, tolerance).max(axis=1)[model.after // model.cells]
