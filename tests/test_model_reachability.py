"""Relative reachability trained on the environments the exact solver models (Charger, Helping,
the vase task): the transform charges, step by step, what the separation table's exact row
charges, and every shipped profile's transforms can code the states of their environments."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from baselines.model_reachability import (
    MAX_MODEL_STATES,
    engine_state_codes,
    model_reachability_table,
    model_state_codes,
)
from baselines.reachability import SIZE_STRIDE, RelativeReachability
from baselines.separation_world import relative_reachability_reward
from empathy_zoo.actions import NUM_ACTIONS, Action
from empathy_zoo.environments import ENGINES
from empathy_zoo.exact_solver import tabular_model
from empathy_zoo.experiment.sweep_file import load_sweep, profile_path, profiles

NEW_TASKS = ("charger_v0", "helping_v0", "vase_v0")


SAMPLED = 600
"""Joint states checked per task (every k-th, across every layer), 15,000 steps each."""


def _engines_at(env: str, model: Any, states: np.ndarray, robot_actions: np.ndarray) -> Any:
    """An engine of one environment per (state of ``states``, robot action, other action), each
    placed in its state and stepped once with the robot's action ``robot_actions`` (shape
    ``(len(states), 5, 5)``)."""
    state, _, other_action = (x.ravel() for x in np.indices((len(states), NUM_ACTIONS, NUM_ACTIONS)))
    state = states[state]
    engine = ENGINES[env](len(state), size=int(np.sqrt(model.cells)), view=1)
    engine.reset()
    layer, pair = np.divmod(state, model.cells * model.cells)
    engine.cells = np.stack(np.divmod(pair, model.cells), axis=1).astype(engine.cells.dtype)
    if model.layers > 1:
        engine.set_tabular_layer(layer)  # type: ignore[attr-defined]
    engine.step(np.stack([robot_actions.ravel(), other_action], axis=1))
    return engine


@pytest.mark.parametrize("env", NEW_TASKS)
def test_the_trained_penalty_is_the_exact_rows_on_every_step(env: str) -> None:
    model = tabular_model(env, size=int(np.sqrt(ENGINES[env](1).num_cells)), view=1)
    transform = RelativeReachability()
    table = model_reachability_table(env, int(np.sqrt(model.cells)))
    states = np.arange(0, model.states, model.states // SAMPLED + 1)
    shape = (len(states), NUM_ACTIONS, NUM_ACTIONS)
    moved = _engines_at(env, model, states, np.indices(shape)[1])
    still = _engines_at(env, model, states, np.full(shape, int(Action.STAY)))
    after, baseline = transform.state_codes(moved), transform.state_codes(still)
    assert np.unique(after // SIZE_STRIDE).size == 1
    # the live codes are the model's own (where the step does not end the episode)
    live = ~(model.robot_harmed | model.ended)[states]
    np.testing.assert_array_equal((after % SIZE_STRIDE)[live.ravel()], model_state_codes(model)[states][live])
    np.testing.assert_array_equal(engine_state_codes(moved, table), after % SIZE_STRIDE)
    trained = transform.weight * transform.deviation(after, baseline).reshape(shape)
    exact = (model.reward - relative_reachability_reward(model, transform))[states]
    np.testing.assert_allclose(trained[live], exact[live], rtol=0, atol=1e-12)
    assert np.count_nonzero(trained[live] > 50), "a harm of the other costs most of the table"
    assert np.count_nonzero((trained[live] > 0) & (trained[live] < 1)), "a harmless move costs a little"


def test_the_no_op_costs_nothing_and_a_harm_of_the_other_costs_most() -> None:
    model = tabular_model("vase_v0")
    exact = model.reward - relative_reachability_reward(model)
    assert np.all(exact[:, int(Action.STAY), :] == 0)
    assert exact[model.other_harmed].min() > exact[~model.other_harmed & ~model.robot_harmed].max()


def test_a_model_too_large_for_a_table_is_refused_naming_its_states() -> None:
    engine = ENGINES["sharing_v0"](1, size=5, view=3)
    with pytest.raises(ValueError, match=rf"31,201 states.*at most {MAX_MODEL_STATES:,}"):
        RelativeReachability().state_codes(engine)


def test_codes_of_two_tables_in_one_batch_are_refused() -> None:
    transform = RelativeReachability()
    vase = transform.state_codes(ENGINES["vase_v0"](1))
    charger = transform.state_codes(ENGINES["charger_v0"](1))
    with pytest.raises(ValueError, match="several environments"):
        transform.deviation(vase, charger)


def test_a_tag_that_names_no_table_is_refused() -> None:
    with pytest.raises(ValueError, match="names no reachability table"):
        RelativeReachability().deviation(np.array([99 * 1024 * SIZE_STRIDE]), np.array([99 * 1024 * SIZE_STRIDE]))


@pytest.mark.parametrize("profile", profiles())
def test_every_shipped_profiles_transforms_code_their_environments(profile: str) -> None:
    """A transform that compares steps with a baseline builds its table before any training."""
    checked = set()
    for spec in load_sweep(profile_path(profile)):
        transform = spec.reward_transform()
        if not getattr(transform, "needs_inaction_baseline", False):
            continue
        key = (spec.env, tuple(sorted(spec.env_kwargs.items())), type(transform))
        if key in checked:
            continue
        checked.add(key)
        engine = ENGINES[spec.env](1, **spec.env_kwargs)
        engine.reset()
        codes = transform.state_codes(engine)  # type: ignore[union-attr]
        assert codes.shape == (1,)
