"""# Relative reachability and AUP on the exact model of any environment

The separation table's rows of the two methods that penalise a change to the world, whoever cares
about it, on a :class:`empathy_zoo.exact_solver.TabularModel`: the two cells, and where the engine
has a state beyond them (``layers > 1``: the vase task, Sharing's batteries) that state too. Every
state of the model is a state here: each joint state, the robot alone in each cell and layer, and
the end (the robot harmed). No rule is written
twice: every transition is the model's, read off the engine.

* :func:`model_reachability`: the fewest steps between every two states, a step reaching ``y``
  from ``x`` when some joint action does (the other's moves counted as if chosen, as
  :mod:`baselines.reachability` reads them).
* :func:`relative_reachability_reward`: ``r − λ·d(s'; b')``, ``b'`` the state the same step reaches
  with the robot's no-op, ``d`` the truncated deviation over every state (λ = 100, γᵣ = 0.99:
  :class:`baselines.reachability.RelativeReachability`'s defaults), no penalty on a step that ends
  the robot.
* :func:`attainable_utility_reward`: ``r − λ·Σᵢ |Qᵢ(s, a) − Qᵢ(s, ∅)| / Σᵢ |Qᵢ(s, ∅)|`` with the
  auxiliary values ``Qᵢ`` exact: ``Rᵢ(s') = wᵢ · o(s') / V`` of the robot's observation ``o`` of the
  state reached, the weights of the run of seed 0 (:func:`baselines.aup.auxiliary_reward_map`),
  30 of them, λ = 100/1.501 (:class:`baselines.aup.AttainableUtility`'s defaults). The table's AUP
  row is therefore seed 0's.

Both rewards apply while the other is present; once it is gone the model pays the robot as the
engine does (:func:`empathy_zoo.exact_solver.optimal_values`), and every row acts alike.
"""

from __future__ import annotations

from typing import cast

import numpy as np

from baselines.aup import NO_OP, AttainableUtility, auxiliary_reward_map
from baselines.model_reachability import model_state_codes as state_codes
from baselines.model_reachability import model_successors, reachability_powers
from baselines.reachability import RelativeReachability, truncated_deviation
from baselines.reachability_table import _shortest_steps
from empathy_zoo.actions import NUM_ACTIONS
from empathy_zoo.environments import ENGINES
from empathy_zoo.exact_solver import LayeredEngine, TabularModel

__all__ = ["state_codes", "model_reachability", "relative_reachability_reward", "attainable_utility_reward", "AUP_SEED"]

AUP_SEED = 0
"""The run seed whose auxiliary rewards the exact AUP row uses."""
PAIR_CHUNK = 1024
"""Pairs of a state reached and its baseline whose deviations are computed at once."""


def model_reachability(model: TabularModel, discount: float) -> np.ndarray:
    """``(S, S)``: ``discount ** (fewest steps from x to y)``, 0 where none reach it, over every
    state of the model (see the module page)."""
    return reachability_powers(discount)[_shortest_steps(model_successors(model))]


def relative_reachability_reward(model: TabularModel, transform: RelativeReachability | None = None) -> np.ndarray:
    """The model's shape: its reward less ``λ·d(s'; b')`` (see the module page). The deviation is
    computed once for each pair of a state reached and its baseline that differ (0 where they are
    one state), from the fewest steps between states, :data:`PAIR_CHUNK` rows of reachability at a
    time (Sharing's 31,201 states would take 7.8 GB as one matrix of reachability)."""
    transform = RelativeReachability() if transform is None else transform
    distances = _shortest_steps(model_successors(model))
    powers = reachability_powers(transform.discount)
    codes = state_codes(model)
    baseline = np.broadcast_to(codes[:, NO_OP : NO_OP + 1, :], codes.shape)
    moved = codes != baseline
    keys, inverse = np.unique(codes[moved] * len(distances) + baseline[moved], return_inverse=True)
    after, before = np.divmod(keys, len(distances))
    found = np.zeros(len(keys))
    for start in range(0, len(keys), PAIR_CHUNK):
        part = slice(start, start + PAIR_CHUNK)
        found[part] = truncated_deviation(powers[distances[after[part]]], powers[distances[before[part]]])
    deviation = np.zeros(codes.shape)
    deviation[moved] = found[inverse]
    return model.reward - transform.weight * np.where(model.robot_harmed | model.ended, 0.0, deviation)


def _observations(model: TabularModel) -> np.ndarray:
    """``(S, V)``: the robot's observation of every state (zeros for the end)."""
    engine_class = ENGINES[model.env]
    pairs = model.cells * model.cells
    joint = np.arange(model.states)
    alone = np.arange(model.alone_states)
    layer = np.concatenate([joint // pairs, alone // model.cells])
    robot = np.concatenate([(joint % pairs) // model.cells, alone % model.cells])
    other = np.concatenate([joint % model.cells, np.zeros_like(alone)])
    engine = engine_class(len(layer), **model.env_kwargs)
    engine.reset()
    engine.cells = np.stack([robot, other], axis=1).astype(engine.cells.dtype)
    engine.present[model.states :, 1] = False
    if model.layers > 1:  # (a model of the cells only has no layer to set)
        cast(LayeredEngine, engine).set_tabular_layer(layer)
    seen = np.asarray(engine.observe(0), dtype=np.float64)
    return np.concatenate([seen, np.zeros((1, seen.shape[1]))])


def auxiliary_values(model: TabularModel, gamma: float, seed: int = AUP_SEED, tolerance: float = 1e-10) -> np.ndarray:
    """``(states, 5, N)``: the exact ``Qᵢ(s, a)`` of every auxiliary reward at every joint state,
    the other moving uniformly at random, the robot greedy on each ``Rᵢ``."""
    aup = AttainableUtility()
    observations = _observations(model)
    rewards = observations @ auxiliary_reward_map(seed, observations.shape[1], aup.num_rewards).astype(np.float64)
    rewards /= observations.shape[1]
    rewards[-1] = 0.0  # (the end pays nothing and leads nowhere)
    successors = model_successors(model).reshape(-1, NUM_ACTIONS, model.other_moves)
    live = np.ones(len(successors), dtype=bool)
    live[-1] = False
    v = np.zeros(rewards.shape)
    for _ in range(100_000):
        q = (rewards[successors] + gamma * v[successors]).mean(axis=2)  # (S, 5, N): the other's moves averaged
        v_next = np.where(live[:, None], q.max(axis=1), 0.0)
        change = float(np.abs(v_next - v).max())
        v = v_next
        if gamma / (1.0 - gamma) * change < tolerance:
            break
    return q[: model.states]


def attainable_utility_reward(model: TabularModel, gamma: float = 0.99) -> np.ndarray:
    """The model's shape: its reward less AUP's penalty of the robot's action (see the module page)."""
    q = auxiliary_values(model, gamma)
    shift = np.abs(q - q[:, NO_OP : NO_OP + 1, :]).sum(axis=2)
    scale = np.abs(q[:, NO_OP, :]).sum(axis=1, keepdims=True)
    penalty = AttainableUtility().penalty_weight * np.divide(shift, scale, out=np.zeros_like(shift), where=scale > 0)
    return model.reward - penalty[:, :, None]
