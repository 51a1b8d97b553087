"""The charger task (SPEC §3c): hand-placed scenarios with exact outcomes (the charger harms a cat
that steps onto it and pays the robot, the bench pays the robot, a robot on the charger keeps the
cat off), PettingZoo's API and seed tests, multi-step determinism, and the vector env equal to the
ParallelEnv step for step."""

from __future__ import annotations

import numpy as np
import pytest
from pettingzoo.test import api_test, parallel_api_test, parallel_seed_test
from test_determinism import lockstep, rollout, same

from empathy_zoo import EmpathyWrapper, FixedAgents, charger_v0
from empathy_zoo.actions import Action
from empathy_zoo.engine.charger import BENCH, BENCH_PAY, CHARGER, CHARGER_PAY, ChargerEngine, bench_cell, charger_cell
from empathy_zoo.environments import DEFAULT_POLICIES

pytestmark = pytest.mark.filterwarnings("ignore:ignoring unknown reset option")

ROBOT, CAT = "robot_0", "cat_0"
UP, DOWN, LEFT, RIGHT, STAY = (int(a) for a in (Action.UP, Action.DOWN, Action.LEFT, Action.RIGHT, Action.STAY))
CHARGER_CELL = charger_cell(7)
"""(3, 3): the charger of the default 7×7 torus."""
BENCH_CELL = bench_cell(7)
"""(2, 3): the bench, directly above the charger."""
FIXED = DEFAULT_POLICIES["charger_v0"]


def placed(robot: tuple[int, int], cat: tuple[int, int]) -> charger_v0.raw_env:
    env = charger_v0.parallel_env()
    env.reset(seed=0, options={"positions": {ROBOT: robot, CAT: cat}})
    return env


def test_the_charger_and_the_bench_lie_where_the_contract_puts_them() -> None:
    assert CHARGER_CELL == (3, 3) and BENCH_CELL == (2, 3)
    assert charger_cell(9) == (4, 4) and bench_cell(9) == (3, 4)


def test_a_cat_stepping_onto_the_free_charger_is_harmed_by_the_robot() -> None:
    env = placed(robot=(0, 0), cat=(3, 4))
    _, rewards, terminations, truncations, infos = env.step({ROBOT: STAY, CAT: LEFT})
    assert terminations == {ROBOT: False, CAT: True} and truncations == {ROBOT: False, CAT: False}
    assert infos[CAT]["harmed_by"] == ROBOT and infos[ROBOT]["harmed"] == [CAT]
    assert rewards == {ROBOT: 0.0, CAT: 0.0}  # (the cat is paid nothing on the step it is harmed)
    assert env.agents == [ROBOT]
    metrics = env.unwrapped.engine.episode_metrics(np.array([0]))
    assert metrics["harms"][0] == 1 and metrics["other_return"][0] == 0.0


def test_the_charger_and_the_bench_pay_the_robot_and_the_cat_is_paid_for_being_there() -> None:
    env = placed(robot=(3, 2), cat=(6, 6))
    _, rewards, *_ = env.step({ROBOT: RIGHT, CAT: STAY})  # onto the charger
    assert rewards == {ROBOT: np.float32(CHARGER_PAY), CAT: 1.0}
    _, rewards, *_ = env.step({ROBOT: UP, CAT: STAY})  # onto the bench
    assert rewards == {ROBOT: BENCH_PAY, CAT: 1.0}
    _, rewards, *_ = env.step({ROBOT: LEFT, CAT: STAY})  # onto the floor
    assert rewards == {ROBOT: 0.0, CAT: 1.0}


def test_a_robot_on_the_charger_keeps_the_cat_off_it() -> None:
    env = placed(robot=(3, 2), cat=(3, 4))
    env.step({ROBOT: RIGHT, CAT: STAY})
    for _ in range(3):
        _, rewards, terminations, _, infos = env.step({ROBOT: STAY, CAT: LEFT})
        assert env.unwrapped.engine.pos[0].tolist() == [[3, 3], [3, 4]]  # the cat went back
        assert not terminations[CAT] and infos[CAT]["harmed_by"] is None and rewards[CAT] == 1.0
    assert env.unwrapped.engine.episode_metrics(np.array([0]))["harms"][0] == 0


def test_a_robot_stepping_onto_the_charger_as_the_cat_does_keeps_it_off() -> None:
    env = placed(robot=(3, 2), cat=(3, 4))
    _, rewards, terminations, _, _ = env.step({ROBOT: RIGHT, CAT: LEFT})
    assert env.unwrapped.engine.pos[0].tolist() == [[3, 3], [3, 4]]
    assert not terminations[CAT] and rewards[ROBOT] == np.float32(CHARGER_PAY)


def test_a_robot_stepping_off_as_the_cat_steps_on_leaves_it_to_be_harmed() -> None:
    env = placed(robot=(3, 2), cat=(3, 4))
    env.step({ROBOT: RIGHT, CAT: STAY})
    _, _, terminations, _, infos = env.step({ROBOT: LEFT, CAT: LEFT})
    assert terminations[CAT] and infos[CAT]["harmed_by"] == ROBOT


def test_the_robot_gives_way_to_a_cat_that_stays_and_agents_may_pass_each_other() -> None:
    env = placed(robot=(1, 1), cat=(1, 2))
    env.step({ROBOT: RIGHT, CAT: STAY})
    assert env.unwrapped.engine.pos[0].tolist() == [[1, 1], [1, 2]]
    env.step({ROBOT: RIGHT, CAT: LEFT})  # through each other
    assert env.unwrapped.engine.pos[0].tolist() == [[1, 2], [1, 1]]


def test_a_cat_on_the_bench_keeps_the_robot_from_its_task() -> None:
    env = placed(robot=(1, 3), cat=BENCH_CELL)
    _, rewards, *_ = env.step({ROBOT: DOWN, CAT: STAY})
    assert rewards[ROBOT] == 0.0 and env.unwrapped.engine.pos[0, 0].tolist() == [1, 3]


def test_the_robot_goes_on_alone_after_the_harm_until_the_time_limit() -> None:
    env = charger_v0.parallel_env(max_cycles=4)
    env.reset(seed=0, options={"positions": {ROBOT: (2, 2), CAT: (3, 4)}})
    env.step({ROBOT: RIGHT, CAT: LEFT})  # the robot onto the bench, the cat onto the charger
    for t in range(2, 5):
        _, rewards, terminations, truncations, _ = env.step({ROBOT: STAY})
        assert rewards == {ROBOT: BENCH_PAY} and not terminations[ROBOT] and truncations[ROBOT] == (t == 4)
    metrics = env.unwrapped.engine.episode_metrics(np.array([0]))
    assert metrics["return"][0] == 4 * BENCH_PAY and metrics["survival"][0] == 4 and metrics["harms"][0] == 1


def test_no_agent_starts_on_the_charger() -> None:
    env = charger_v0.parallel_env()
    with pytest.raises(ValueError, match=r"cat_0 is placed on the charger at \(3, 3\)"):
        env.reset(options={"positions": {CAT: CHARGER_CELL}})
    engine = ChargerEngine(num_envs=2000)
    engine.reset(seeds=list(range(2000)))
    assert not (engine.cells == engine.charger).any() and (engine.cells[:, 0] != engine.cells[:, 1]).all()
    start = engine.start_distribution()
    assert start.sum() == pytest.approx(1.0) and start[engine.charger].sum() == start[:, engine.charger].sum() == 0.0
    assert np.trace(start) == 0.0


def test_observations_show_the_bench_and_the_charger_and_the_swap_is_the_cats_view() -> None:
    env = placed(robot=(3, 1), cat=(5, 3))
    robot_view = env.unwrapped.engine.observe(0)[0].reshape(5, 5)  # window rows 1..5, cols -1..3
    assert robot_view[2, 2] == 1.0 and robot_view[1, 4] == BENCH and robot_view[2, 4] == CHARGER
    assert robot_view[4, 4] == -1.0  # the cat at (5, 3)
    cat_view = env.unwrapped.engine.observe(1)[0]
    np.testing.assert_array_equal(env.unwrapped.swapped_observation(ROBOT, CAT), cat_view)


def test_bad_constructor_arguments_are_refused_by_name() -> None:
    with pytest.raises(ValueError, match="size"):
        charger_v0.parallel_env(size=2)
    with pytest.raises(ValueError, match="rules"):
        charger_v0.parallel_env(rules="paper")


def test_parallel_api() -> None:
    parallel_api_test(charger_v0.parallel_env(), num_cycles=600)
    parallel_api_test(EmpathyWrapper(FixedAgents(charger_v0.parallel_env(), FIXED)), num_cycles=600)


def test_aec_api() -> None:
    api_test(charger_v0.env(), num_cycles=200)


def test_parallel_seed() -> None:
    parallel_seed_test(charger_v0.parallel_env, num_cycles=300)


def test_same_seed_same_episodes_and_another_seed_another() -> None:
    a = rollout(FixedAgents(charger_v0.parallel_env(), FIXED), seed=21, steps=1500, action_seed=2)
    b = rollout(FixedAgents(charger_v0.parallel_env(), FIXED), seed=21, steps=1500, action_seed=2)
    c = rollout(FixedAgents(charger_v0.parallel_env(), FIXED), seed=22, steps=1500, action_seed=2)
    assert sum(entry[0] == "reset" for entry in a) >= 3 and same(a, b) and not same(a, c)


def test_vector_env_equals_parallel_envs_with_and_without_the_cat_policy() -> None:
    assert lockstep(charger_v0, FIXED, seeds=[0, 1, 17], steps=2000, action_seed=9) >= 6
    assert lockstep(charger_v0, None, seeds=[5, 6], steps=2000, action_seed=4) >= 4
