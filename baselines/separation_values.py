"""The values two empathic rows of the separation table act on, at ``Q*`` of a
:class:`empathy_zoo.exact_solver.TabularModel` (:mod:`baselines.separation` holds the table).

* :func:`silver_values`: the silver rule as implemented (:mod:`baselines.silver_rule`),
  ``Q* − (1 − β)·E[max(c − o, 0)]``, ``c = γ·(1 − done)·V*(s')`` and ``o = γ·present'·V*(swap(s'))``
  (``present'`` 0 where the other is harmed, or where the episode ends for both: it is terminal).
* :func:`in_view_values`: in-view Empathic DQN, the golden rule with the robot's own continuation as
  the other-term wherever the other is present but outside the engine's window at t+1 (SPEC §4).

Once the other is gone the robot's continuation is
:func:`empathy_zoo.exact_solver.gone_continuation`'s.
"""

from __future__ import annotations

import numpy as np

from empathy_zoo.environments import ENGINES
from empathy_zoo.exact_solver import TabularModel, gone_continuation

__all__ = ["silver_values", "in_view_values"]


def _continuation(model: TabularModel, v: np.ndarray, gamma: float) -> np.ndarray:
    """``c = γ·(1 − done)·V*(s')`` of every step (the model's shape), the robot alone once the other
    leaves; ``done`` where the robot is harmed or the episode ends for both."""
    ends = model.robot_harmed | model.ended
    return np.select([ends, model.other_harmed], [0.0, gone_continuation(model, gamma)], gamma * v[model.after])


def silver_values(model: TabularModel, selfishness: float, q: np.ndarray, gamma: float = 0.99) -> np.ndarray:
    """The silver rule's ``Q_silver = Q* − (1 − β)·E[max(c − o, 0)]`` at ``Q*`` (the module page)."""
    v = q.max(axis=1)
    continuation = _continuation(model, v, gamma)
    other = gamma * np.where(model.other_harmed | model.ended, 0.0, v[model.swapped][model.after])
    return q - (1.0 - selfishness) * np.maximum(continuation - other, 0.0).mean(axis=2)


def in_view_values(model: TabularModel, selfishness: float, q: np.ndarray, gamma: float = 0.99) -> np.ndarray:
    """In-view Empathic DQN's target at ``Q*``: the golden rule, with the robot's own continuation
    as the other-term where the other is present but outside the engine's window at t+1."""
    engine = ENGINES[model.env](model.states, **model.env_kwargs)
    engine.reset()
    engine.cells = np.stack(np.divmod(np.arange(model.states) % (model.cells * model.cells), model.cells), axis=1).astype(
        engine.cells.dtype
    )
    seen = np.asarray(engine.in_view(0, 1), dtype=bool)
    v = q.max(axis=1)
    continuation = _continuation(model, v, gamma)
    terminal = model.other_harmed | model.ended
    other = gamma * np.where(terminal, 0.0, v[model.swapped][model.after])
    other = np.where(~terminal & ~seen[model.after], continuation, other)
    return q + (1.0 - selfishness) * (other - model.reward - continuation).mean(axis=2)
