"""Exact reachability between the states of an environment's exact model, and the codes of a
live engine's states in it.

Relative reachability (:mod:`baselines.reachability`) needs the fewest steps between every two
states. On Coexistence with one cat it reads them from its own table
(:mod:`baselines.reachability_table`). On every other environment the exact solver models (one
learner and one other agent, :func:`empathy_zoo.exact_solver.tabular_model`: Charger, Helping,
the vase task) it reads them from that model, so a trained run and the separation table's exact
row (:mod:`baselines.separation_world`) charge the same deviation for the same step.

A state of the model is each joint state (``layer · cells² + robot cell · cells + other cell``),
the robot alone in each cell and layer (``states + layer · cells + cell``) and the end (the robot
harmed, or the episode over for both: ``states + alone_states``). A step reaches ``y`` from ``x``
when some joint action does, the other's moves counted as if chosen (as
:mod:`baselines.reachability` reads them). Every transition is the model's, read off the engine;
no rule is written here.

The table holds ``|S|²`` bytes, at most :data:`MAX_MODEL_STATES` states (100 MB): 2,451 states
on Charger (size 7), 2,601 on Helping (size 5), 1,301 on the vase task (size 5). Building it
holds several arrays of that size at once: about 655 MB at its peak, in 4 s, for the largest
allowed (Helping on a 7 × 7 grid, 9,801 states). Sharing's 31,201 states (size 5) are refused.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import cast

import numpy as np

from baselines.reachability_table import _discounted as reachability_powers
from baselines.reachability_table import _shortest_steps
from empathy_zoo.actions import NUM_ACTIONS
from empathy_zoo.engine import GridEngine
from empathy_zoo.environments import ENGINES
from empathy_zoo.exact_solver import LayeredEngine, TabularModel, tabular_model

__all__ = [
    "MAX_MODEL_STATES",
    "ModelReachability",
    "engine_state_codes",
    "model_reachability_table",
    "model_state_count",
    "model_state_codes",
    "model_successors",
    "reachability_powers",
]

MAX_MODEL_STATES = 10_000
"""Most states of a model whose reachability table is built (``|S|²`` bytes: 100 MB; about
6.5 times that while it is built)."""
ROBOT, OTHER = 0, 1


def model_state_codes(model: TabularModel) -> np.ndarray:
    """The model's shape: the code of the state each step ends in: a joint state's own index, the
    robot alone ``states + layer · cells + cell``, the end ``states + alone_states``."""
    end = model.states + model.alone_states
    ends = model.robot_harmed | model.ended
    return np.select([ends, model.other_harmed], [end, model.states + model.after // model.cells], model.after)


def model_successors(model: TabularModel) -> np.ndarray:
    """``(states + alone_states + 1, 25)``: the code every joint action leads to from every state."""
    end = model.states + model.alone_states
    width = NUM_ACTIONS * model.other_moves
    joint = model_state_codes(model).reshape(model.states, width)
    alone = np.repeat(model.states + model.alone_after, model.other_moves, axis=1)
    return np.concatenate([joint, alone, np.full((1, width), end)])


def _probe(env: str, size: int) -> GridEngine:
    """One environment of ``env``'s engine on a ``size × size`` grid (``view = 1``: the model
    does not depend on what the agents see)."""
    return cast(GridEngine, ENGINES[env](1, size=size, view=1))


def model_state_count(env: str, size: int) -> int:
    """``|S|`` of ``env``'s model on a ``size × size`` grid (joint states, the robot alone, the end)."""
    probe = _probe(env, size)
    layers = int(getattr(probe, "tabular_layers", 1))
    return layers * probe.num_cells * probe.num_cells + layers * probe.num_cells + 1


@dataclass(frozen=True)
class ModelReachability:
    """The fewest steps between every two states of one environment's exact model."""

    env: str
    """The environment."""
    size: int
    """The grid's side."""
    cells: int
    """Cells of the grid."""
    layers: int
    """Values of the state beyond the two cells."""
    distances: np.ndarray
    """``(|S|, |S|)`` uint8: ``[x, y]`` the fewest steps from state ``x`` to ``y``,
    :data:`UNREACHABLE` where none reach it."""

    @property
    def num_states(self) -> int:
        """``|S|``."""
        return len(self.distances)

    def reachability(self, codes: np.ndarray, discount: float) -> np.ndarray:
        """``(*codes.shape, |S|)`` float64: ``R(x; s) = discount ** distance(x, s)`` (0 where
        unreachable) from each state of ``codes`` to every state ``s``."""
        codes = np.asarray(codes, dtype=np.int64)
        if codes.size and (codes.min() < 0 or codes.max() >= self.num_states):
            raise ValueError(f"state codes of {self.env} (size {self.size}) must be in [0, {self.num_states})")
        return reachability_powers(discount)[self.distances[codes]]


@functools.lru_cache(maxsize=4)
def model_reachability_table(env: str, size: int) -> ModelReachability:
    """The :class:`ModelReachability` of ``env`` on a ``size × size`` grid, built once per process;
    ``ValueError`` for an environment the exact solver does not model or a model of more than
    :data:`MAX_MODEL_STATES` states."""
    if env not in ENGINES:
        raise ValueError(f"unknown environment {env!r}; registered: {sorted(ENGINES)}")
    count = model_state_count(env, size)
    if count > MAX_MODEL_STATES:
        raise ValueError(
            f"{env} on size={size} has {count:,} states; an exact reachability table is built for at most "
            f"{MAX_MODEL_STATES:,} (its |S|² bytes)"
        )
    model = tabular_model(env, size=size, view=1)
    distances = _shortest_steps(model_successors(model))
    distances.flags.writeable = False
    return ModelReachability(env=env, size=size, cells=model.cells, layers=model.layers, distances=distances)


def engine_state_codes(engine: GridEngine, table: ModelReachability) -> np.ndarray:
    """``(N,)`` the codes in ``table``'s model of the states of ``engine``'s ``N`` environments
    (the robot absent: the end; the other absent: the robot alone in its cell and layer)."""
    cells = table.cells
    robot, other = engine.cells[:, ROBOT].astype(np.int64), engine.cells[:, OTHER].astype(np.int64)
    layer = (
        np.asarray(cast(LayeredEngine, engine).tabular_layer(), dtype=np.int64)
        if table.layers > 1
        else np.zeros(len(robot), dtype=np.int64)
    )
    joint = layer * cells * cells + robot * cells + other
    states = table.layers * cells * cells
    alone = states + layer * cells + robot
    end = states + table.layers * cells
    return np.where(~engine.present[:, ROBOT], end, np.where(~engine.present[:, OTHER], alone, joint))
