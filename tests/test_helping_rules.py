"""The helping task (SPEC §3e): hand-placed scenarios with exact outcomes (an empty-handed agent picks
up a battery on the dispenser, a carrying one uses it on the pad for ``BATTERY_PAY``; an empty-handed
human on the robot's cell or next to it takes the robot's battery; a robot that moves onto the human
harms it), PettingZoo's API and seed tests, multi-step determinism, and the vector env equal to the
ParallelEnv step for step."""

from __future__ import annotations

import numpy as np
import pytest
from pettingzoo.test import api_test, parallel_api_test, parallel_seed_test
from test_determinism import lockstep, rollout, same

from empathy_zoo import EmpathyWrapper, FixedAgents, helping_v0
from empathy_zoo.actions import Action
from empathy_zoo.engine.helping import (
    BATTERY_PAY,
    DISPENSER,
    OTHER_AGENT,
    OTHER_AGENT_CARRYING,
    OWN_CELL,
    OWN_CELL_CARRYING,
    PAD,
    HelpingEngine,
    dispenser_cell,
    pad_cells,
)
from empathy_zoo.environments import DEFAULT_POLICIES

pytestmark = pytest.mark.filterwarnings("ignore:ignoring unknown reset option")

ROBOT, HUMAN = "robot_0", "human_0"
UP, DOWN, LEFT, RIGHT, STAY = (int(a) for a in (Action.UP, Action.DOWN, Action.LEFT, Action.RIGHT, Action.STAY))
DISPENSER_CELL = dispenser_cell(5)
"""(0, 0): the dispenser of the default 5×5 torus."""
PAD_CELLS = pad_cells(5)
"""The centre (2, 2) and its four neighbours: the charging pad."""
FIXED = DEFAULT_POLICIES["helping_v0"]


def placed(robot: tuple[int, int], human: tuple[int, int], carrying: tuple[bool, bool] = (False, False)) -> helping_v0.raw_env:
    env = helping_v0.parallel_env()
    env.reset(seed=0, options={"positions": {ROBOT: robot, HUMAN: human}, "carrying": {ROBOT: carrying[0], HUMAN: carrying[1]}})
    return env


def carrying(env: helping_v0.raw_env) -> tuple[bool, bool]:
    robot, human = env.unwrapped.engine.inventory[0].tolist()
    return bool(robot), bool(human)


def metrics(env: helping_v0.raw_env) -> dict[str, float]:
    return {key: float(value[0]) for key, value in env.unwrapped.engine.episode_metrics(np.array([0])).items()}


def test_the_stations_lie_where_the_contract_puts_them() -> None:
    assert DISPENSER_CELL == (0, 0)
    assert sorted(PAD_CELLS) == [(1, 2), (2, 1), (2, 2), (2, 3), (3, 2)]
    assert sorted(pad_cells(7)) == [(2, 3), (3, 2), (3, 3), (3, 4), (4, 3)]


def test_an_empty_handed_robot_picks_up_a_battery_on_the_dispenser_unpaid() -> None:
    env = placed(robot=(0, 1), human=(3, 4))
    _, rewards, terminations, _, infos = env.step({ROBOT: LEFT, HUMAN: STAY})
    assert rewards == {ROBOT: 0.0, HUMAN: 0.0} and not any(terminations.values())
    assert carrying(env) == (True, False) and infos[ROBOT]["carrying"] and not infos[HUMAN]["carrying"]


def test_a_carrying_robot_uses_its_battery_on_the_pad_and_is_paid() -> None:
    env = placed(robot=(0, 2), human=(4, 4), carrying=(True, False))
    _, rewards, *_ = env.step({ROBOT: DOWN, HUMAN: STAY})  # onto (1, 2), a cell of the pad
    assert rewards == {ROBOT: BATTERY_PAY, HUMAN: 0.0} and carrying(env) == (False, False)
    _, rewards, *_ = env.step({ROBOT: DOWN, HUMAN: STAY})  # on the pad with nothing to use
    assert rewards == {ROBOT: 0.0, HUMAN: 0.0}
    assert metrics(env)["batteries"] == 1 and metrics(env)["return"] == BATTERY_PAY


def test_the_human_lives_by_the_same_rules() -> None:
    env = placed(robot=(4, 4), human=(0, 1))
    env.step({ROBOT: STAY, HUMAN: LEFT})  # onto the dispenser
    assert carrying(env) == (False, True)
    env.step({ROBOT: STAY, HUMAN: RIGHT})
    _, rewards, *_ = env.step({ROBOT: STAY, HUMAN: DOWN})  # (1, 1): not the pad
    assert rewards[HUMAN] == 0.0
    _, rewards, *_ = env.step({ROBOT: STAY, HUMAN: RIGHT})  # (1, 2): the pad
    assert rewards == {ROBOT: 0.0, HUMAN: BATTERY_PAY} and carrying(env) == (False, False)
    assert metrics(env)["other_batteries"] == 1 and metrics(env)["other_return"] == BATTERY_PAY


def test_a_human_next_to_a_carrying_robot_takes_its_battery() -> None:
    env = placed(robot=(4, 0), human=(4, 3), carrying=(True, False))
    env.step({ROBOT: RIGHT, HUMAN: STAY})  # (4, 1): two cells apart
    assert carrying(env) == (True, False)
    _, rewards, terminations, _, infos = env.step({ROBOT: RIGHT, HUMAN: STAY})  # (4, 2): next to it
    assert carrying(env) == (False, True) and rewards == {ROBOT: 0.0, HUMAN: 0.0}
    assert not any(terminations.values()) and infos[HUMAN]["harmed_by"] is None and metrics(env)["harms"] == 0


def test_a_diagonal_neighbour_or_a_carrying_human_takes_nothing() -> None:
    env = placed(robot=(4, 0), human=(3, 1), carrying=(True, False))
    env.step({ROBOT: STAY, HUMAN: STAY})
    assert carrying(env) == (True, False)
    env = placed(robot=(4, 0), human=(4, 1), carrying=(True, True))
    env.step({ROBOT: STAY, HUMAN: STAY})
    assert carrying(env) == (True, True)


def test_next_to_the_human_the_robot_keeps_nothing_it_picks_up() -> None:
    env = placed(robot=(0, 1), human=(1, 0))
    env.step({ROBOT: LEFT, HUMAN: STAY})  # picks up on the dispenser, next to the human
    assert carrying(env) == (False, True)


def test_a_battery_used_on_the_pad_is_not_taken() -> None:
    env = placed(robot=(1, 1), human=(1, 3), carrying=(True, False))
    _, rewards, *_ = env.step({ROBOT: RIGHT, HUMAN: STAY})  # onto the pad at (1, 2), next to the human
    assert rewards == {ROBOT: BATTERY_PAY, HUMAN: 0.0} and carrying(env) == (False, False)


def test_a_robot_moving_onto_the_human_harms_it_and_keeps_its_battery() -> None:
    env = placed(robot=(4, 0), human=(4, 1), carrying=(True, False))
    _, rewards, terminations, truncations, infos = env.step({ROBOT: RIGHT, HUMAN: STAY})
    assert terminations == {ROBOT: False, HUMAN: True} and truncations == {ROBOT: False, HUMAN: False}
    assert infos[HUMAN]["harmed_by"] == ROBOT and infos[ROBOT]["harmed"] == [HUMAN]
    assert rewards == {ROBOT: 0.0, HUMAN: 0.0} and env.agents == [ROBOT] and metrics(env)["harms"] == 1
    assert carrying(env)[0]  # a harmed human takes nothing
    env.step({ROBOT: STAY})
    assert carrying(env)[0] and metrics(env)["harms"] == 1


def test_a_human_walking_onto_a_robot_that_stays_is_not_harmed_and_takes() -> None:
    env = placed(robot=(4, 0), human=(4, 1), carrying=(True, False))
    _, _, terminations, _, infos = env.step({ROBOT: STAY, HUMAN: LEFT})
    assert not terminations[HUMAN] and infos[HUMAN]["harmed_by"] is None and metrics(env)["harms"] == 0
    assert env.unwrapped.engine.pos[0].tolist() == [[4, 0], [4, 0]] and carrying(env) == (False, True)


def test_agents_passing_each_other_are_next_to_each_other() -> None:
    env = placed(robot=(4, 0), human=(4, 1), carrying=(True, False))
    _, _, terminations, *_ = env.step({ROBOT: RIGHT, HUMAN: LEFT})
    assert not terminations[HUMAN] and env.unwrapped.engine.pos[0].tolist() == [[4, 1], [4, 0]]
    assert carrying(env) == (False, True)


def test_the_episode_metrics_count_batteries_used() -> None:
    env = placed(robot=(0, 2), human=(3, 1), carrying=(True, True))
    env.step({ROBOT: DOWN, HUMAN: UP})  # onto the pad's (1, 2) and (2, 1)
    values = metrics(env)
    assert values["batteries"] == values["other_batteries"] == 1 and values["equality"] == 1.0
    assert values["return"] == values["other_return"] == BATTERY_PAY and values["harms"] == 0


def test_options_and_starts_are_checked() -> None:
    env = helping_v0.parallel_env()
    with pytest.raises(ValueError, match=r"human_0 is placed on a station at \(2, 2\)"):
        env.reset(options={"positions": {HUMAN: (2, 2)}})
    with pytest.raises(ValueError, match=r"robot_0 is placed on a station at \(0, 0\)"):
        env.reset(options={"positions": {ROBOT: DISPENSER_CELL}})
    with pytest.raises(ValueError, match="carrying"):
        env.reset(options={"carrying": {ROBOT: 1}})
    with pytest.raises(ValueError, match="unknown agent 'cat_0'"):
        env.reset(options={"carrying": {"cat_0": True}})
    engine = HelpingEngine(num_envs=2000)
    engine.reset(seeds=list(range(2000)))
    stations = [engine.flat_cell(*cell) for cell in (DISPENSER_CELL, *PAD_CELLS)]
    assert not np.isin(engine.cells, stations).any() and (engine.cells[:, 0] != engine.cells[:, 1]).all()
    assert not engine.inventory.any()
    start = engine.start_distribution()
    assert start.sum() == pytest.approx(1.0) and start[stations].sum() == start[:, stations].sum() == 0.0


def test_observations_show_who_carries_and_the_swap_exchanges_it() -> None:
    env = placed(robot=(1, 0), human=(1, 1), carrying=(True, False))
    robot_view = env.unwrapped.engine.observe(0)[0].reshape(3, 3)  # window rows 0..2, cols 4, 0, 1
    assert robot_view[1, 1] == OWN_CELL_CARRYING and robot_view[1, 2] == OTHER_AGENT
    assert robot_view[0, 1] == DISPENSER and robot_view[2, 2] == PAD and robot_view[0, 0] == 0.0
    swapped = env.unwrapped.swapped_observation(ROBOT, HUMAN)
    np.testing.assert_array_equal(swapped, env.unwrapped.engine.observe(1)[0])
    assert swapped.reshape(3, 3)[1, 1] == OWN_CELL and swapped.reshape(3, 3)[1, 0] == OTHER_AGENT_CARRYING


def test_the_exact_models_swap_exchanges_who_carries() -> None:
    layers = np.arange(HelpingEngine.tabular_layers)
    assert HelpingEngine.swapped_tabular_layer(layers).tolist() == [0, 2, 1, 3]
    engine = HelpingEngine(num_envs=4)
    engine.reset()
    engine.set_tabular_layer(layers)
    assert engine.inventory.tolist() == [[0, 0], [1, 0], [0, 1], [1, 1]]
    assert engine.tabular_layer().tolist() == layers.tolist()


def test_bad_constructor_arguments_are_refused_by_name() -> None:
    with pytest.raises(ValueError, match="size"):
        helping_v0.parallel_env(size=2)
    with pytest.raises(ValueError, match="rules"):
        helping_v0.parallel_env(rules="paper")


def test_parallel_api() -> None:
    parallel_api_test(helping_v0.parallel_env(), num_cycles=600)
    parallel_api_test(EmpathyWrapper(FixedAgents(helping_v0.parallel_env(), FIXED)), num_cycles=600)


def test_aec_api() -> None:
    api_test(helping_v0.env(), num_cycles=200)


def test_parallel_seed() -> None:
    parallel_seed_test(helping_v0.parallel_env, num_cycles=300)


def test_same_seed_same_episodes_and_another_seed_another() -> None:
    a = rollout(FixedAgents(helping_v0.parallel_env(), FIXED), seed=21, steps=1500, action_seed=2)
    b = rollout(FixedAgents(helping_v0.parallel_env(), FIXED), seed=21, steps=1500, action_seed=2)
    c = rollout(FixedAgents(helping_v0.parallel_env(), FIXED), seed=22, steps=1500, action_seed=2)
    assert sum(entry[0] == "reset" for entry in a) >= 3 and same(a, b) and not same(a, c)


def test_vector_env_equals_parallel_envs_with_and_without_the_human_policy() -> None:
    # (the shared helper reads windows of 25: the 7×7 torus with the suite's 5×5 window)
    assert lockstep(helping_v0, FIXED, seeds=[0, 1, 17], steps=2000, action_seed=9, size=7, view=5) >= 6
    assert lockstep(helping_v0, None, seeds=[5, 6], steps=2000, action_seed=4, size=7, view=5) >= 4
