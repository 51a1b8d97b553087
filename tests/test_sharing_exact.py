"""Sharing's exact model (size 5: 4 batteries at the odd cells): the engine's hooks round-trip every
layer and the swap exchanges what each agent holds; the chance node gives a battery both agents
reach to each with probability ½; the model steps as the engine steps with its own generator; the
start distribution is uniform over distinct battery-free cells; a hand-checked ``Q*``; equality
scaling's exact reward; and the stand-in streams of the tabulation with their checks."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from baselines.separation_batteries import battery_figures, equality_reward, layer_figures
from empathy_zoo.actions import NUM_ACTIONS, Action
from empathy_zoo.engine.sharing import SharingEngine, battery_value, tabular_layer_table
from empathy_zoo.exact_chance import FixedDraws, check_draws
from empathy_zoo.exact_solver import alone_policy, optimal_values, outcome, tabular_model
from empathy_zoo.reference import greedy_policy

ARGUMENTS: dict[str, Any] = {"size": 5, "view": 3}
"""The smallest Sharing the exact model enumerates (view 3: the window must be smaller than the grid)."""
SIZE, BATTERIES, LAYERS = 5, 4, 48
"""Side, batteries (the odd cells (1, 1), (1, 3), (3, 1), (3, 3)) and layers of the exact model."""
CELLS = SIZE * SIZE
ROBOT, HUMAN = 0, 1


def flat(row: int, col: int) -> int:
    return row * SIZE + col


def layer_of(left: list[tuple[int, int]], robot: int, human: int) -> int:
    """The layer with the batteries ``left`` and the counts each agent holds, as the engine reads it."""
    engine = SharingEngine(1, **ARGUMENTS)
    engine.reset()
    engine.batteries[:] = False
    for cell in left:
        engine.batteries[0, flat(*cell)] = True
    engine.inventory[0] = (robot, human)
    return int(engine.tabular_layer()[0])


def state_of(layer: int, robot: tuple[int, int], human: tuple[int, int]) -> int:
    return layer * CELLS * CELLS + flat(*robot) * CELLS + flat(*human)


@pytest.fixture(scope="module")
def model():
    return tabular_model("sharing_v0", **ARGUMENTS)


def test_the_hooks_round_trip_every_layer_and_the_swap_exchanges_the_counts() -> None:
    engine = SharingEngine(LAYERS, **ARGUMENTS)
    engine.reset()
    assert engine.tabular_layers == LAYERS
    layers = np.arange(LAYERS)
    engine.set_tabular_layer(layers)
    np.testing.assert_array_equal(engine.tabular_layer(), layers)
    held = engine.inventory.copy()
    left = engine.batteries.sum(axis=1)
    np.testing.assert_array_equal(engine.inventory.sum(axis=1) + left, BATTERIES)  # every battery somewhere
    assert engine.tabular_layer()[0] == 0 and left[0] == BATTERIES and not engine.inventory[0].any()  # the start
    swapped = engine.swapped_tabular_layer(layers)
    np.testing.assert_array_equal(engine.swapped_tabular_layer(swapped), layers)
    engine.set_tabular_layer(swapped)
    np.testing.assert_array_equal(engine.inventory, held[:, ::-1])
    np.testing.assert_array_equal(engine.batteries.sum(axis=1), left)
    bitmap, robot = tabular_layer_table(BATTERIES)
    assert len(set(zip(bitmap.tolist(), robot.tolist(), strict=True))) == LAYERS  # each (batteries left, robot's count) once


def test_the_figures_of_a_layer_are_its_counts_and_their_equality() -> None:
    engine = SharingEngine(1, **ARGUMENTS)
    layer = np.array([layer_of([], 3, 1)])
    figures = engine.tabular_figures(layer)
    robot, human = 1.0 + 0.9 + 0.8, 1.0
    assert figures["batteries"][0] == 3 and figures["other_batteries"][0] == 1
    assert figures["equality"][0] == pytest.approx(2 * human / (robot + human))


def test_the_hooks_refuse_what_they_do_not_model() -> None:
    with pytest.raises(ValueError, match="one learner and one other agent"):
        tabular_model("sharing_v0", num_humans=2, **ARGUMENTS)
    with pytest.raises(ValueError, match="inventory_encoding='count_plus_one'"):
        tabular_model("sharing_v0", inventory_encoding="authors", **ARGUMENTS)
    with pytest.raises(ValueError, match="6,761,216 joint states"):  # the 7×7 default: 2,816 layers × 49²
        tabular_model("sharing_v0")


def test_the_start_is_uniform_over_distinct_battery_free_cells(model) -> None:
    start = model.start.reshape(-1, CELLS, CELLS)
    assert start.sum() == pytest.approx(1.0)
    assert not start[1:].any()  # every battery left, none held
    free = [cell for cell in range(CELLS) if not (cell // SIZE % 2 and cell % SIZE % 2)]
    expected = np.zeros((CELLS, CELLS))
    expected[np.ix_(free, free)] = 1.0 / (len(free) * (len(free) - 1))
    expected[free, free] = 0.0
    np.testing.assert_allclose(start[0], expected)


def test_a_battery_both_agents_reach_goes_to_each_with_probability_one_half(model) -> None:
    assert model.draws == 2 and model.other_moves == 2 * NUM_ACTIONS and model.reward.shape == (30_000, 5, 10)
    start = state_of(0, (1, 0), (1, 2))  # (1, 1) between them
    draws = slice(Action.LEFT * model.draws, (Action.LEFT + 1) * model.draws)  # the human moves left, both draws
    after, reward = model.after[start, Action.RIGHT, draws], model.reward[start, Action.RIGHT, draws]
    other = model.other_reward[start, Action.RIGHT, draws]
    robot_took = state_of(layer_of([(1, 3), (3, 1), (3, 3)], 1, 0), (1, 1), (1, 1))
    human_took = state_of(layer_of([(1, 3), (3, 1), (3, 3)], 0, 1), (1, 1), (1, 1))
    assert sorted(after.tolist()) == sorted([robot_took, human_took])
    assert sorted(zip(reward.tolist(), other.tolist(), strict=True)) == [(0.0, 1.0), (1.0, 0.0)]
    # each draw is one of the model's ten equally likely other moves: each winner has ½ of the human's move left
    weights = np.bincount(model.after[start, Action.RIGHT].ravel(), minlength=model.states) / model.other_moves
    assert weights[robot_took] == weights[human_took] == pytest.approx(0.1)


def test_the_model_steps_as_the_engine_with_its_own_generator(model) -> None:
    rng = np.random.default_rng(0)
    count = 4_000
    state, robot_action, other_action = (
        rng.integers(model.states, size=count),
        rng.integers(5, size=count),
        rng.integers(5, size=count),
    )
    engine = SharingEngine(count, **ARGUMENTS)
    engine.reset(seeds=list(range(count)))
    layer, pair = np.divmod(state, CELLS * CELLS)
    engine.cells = np.stack(np.divmod(pair, CELLS), axis=1)
    engine.set_tabular_layer(layer)
    events = engine.step(np.stack([robot_action, other_action], axis=1))
    after = engine.tabular_layer() * CELLS * CELLS + engine.cells[:, ROBOT] * CELLS + engine.cells[:, HUMAN]
    moves = other_action[:, None] * model.draws + np.arange(model.draws)
    modelled = model.after[state[:, None], robot_action[:, None], moves]
    rewards = model.reward[state[:, None], robot_action[:, None], moves]
    chance = modelled[:, 0] != modelled[:, 1]
    assert chance.any() and (~chance).sum() > count // 2  # some contests in the sample, most steps none
    np.testing.assert_array_equal(after[~chance], modelled[~chance, 0])  # no contest: both draws are the engine's step
    np.testing.assert_array_equal(events.rewards[~chance, ROBOT], rewards[~chance, 0])
    assert ((after[:, None] == modelled).any(axis=1)).all()  # a contest: the engine's winner is one of the two
    np.testing.assert_array_equal(events.terminated[~chance, ROBOT], model.ended[state, robot_action, moves[:, 0]][~chance])


def test_the_last_battery_next_to_the_robot_is_worth_its_value_and_ends_the_episode(model) -> None:
    last = layer_of([(1, 1)], 0, 3)  # the human holds three; the robot's first battery is worth 1.0
    state = state_of(last, (1, 0), (3, 3))  # the human four steps from it
    assert model.ended[state, Action.RIGHT].all() and not model.ended[state, Action.STAY].any()
    q = optimal_values(model)
    assert q[state, Action.RIGHT] == pytest.approx(float(battery_value(1)), abs=1e-12)  # 1.0 + γ·0
    gamma = 0.99  # the human cannot reach it within two steps: a step away from it costs γ, two γ²
    np.testing.assert_allclose(q[state], [gamma**2, gamma**2, gamma**2, 1.0, gamma], atol=1e-12)
    greedy = greedy_policy(q)
    start = np.zeros(model.states)
    start[state] = 1.0
    ends = outcome(_from(model, start), greedy, 500, alone_policy(model, 0.0))
    assert (ends.survival, ends.robot_return, ends.other_return) == pytest.approx((1.0, 1.0, 0.0), abs=1e-12)
    figures = battery_figures(ends, layer_figures(model))
    assert (figures["batteries"], figures["other_batteries"]) == pytest.approx((1.0, 3.0), abs=1e-12)


def _from(model, start: np.ndarray):
    import dataclasses

    return dataclasses.replace(model, start=start)


def test_equality_scaling_pays_a_battery_times_the_equality_after_it(model) -> None:
    reward = equality_reward(model)
    last = layer_of([(1, 1)], 0, 3)
    state = state_of(last, (1, 0), (3, 3))
    robot, human = 1.0, 1.0 + 0.9 + 0.8
    np.testing.assert_allclose(reward[state, Action.RIGHT], 2 * robot / (robot + human))


def test_fixed_draws_and_the_check_of_them() -> None:
    stand_in = FixedDraws(3, draw=1, draws=2)
    assert stand_in.uniform(np.array([0, 2])).tolist() == [0.75, 0.75]
    assert stand_in.drawn.tolist() == [1, 0, 1]
    step = {"after": np.array([1, 2, 3])}
    with pytest.raises(ValueError, match="declares no chance"):
        check_draws("toy", 1, [np.array([0, 1, 0])], [step])
    with pytest.raises(ValueError, match="2 numbers in one step"):
        check_draws("toy", 2, [np.array([0, 2, 0])] * 2, [step, step])
    with pytest.raises(RuntimeError, match="drew nothing otherwise"):
        check_draws("toy", 2, [np.array([0, 1, 0])] * 2, [step, {"after": np.array([1, 5, 4])}])
    check_draws("toy", 2, [np.array([0, 1, 0])] * 2, [step, {"after": np.array([1, 5, 3])}])
