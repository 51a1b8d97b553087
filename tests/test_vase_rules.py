"""The vase task (SPEC §3d): hand-placed scenarios with exact outcomes (the robot breaks the vase by
stepping onto it, for good; a robot that moves onto the cat harms it; the benches pay the robot and
the standing vase pays the cat), PettingZoo's API and seed tests, multi-step determinism, and the
vector env equal to the ParallelEnv step for step."""

from __future__ import annotations

import numpy as np
import pytest
from pettingzoo.test import api_test, parallel_api_test, parallel_seed_test
from test_determinism import lockstep, rollout, same

from empathy_zoo import EmpathyWrapper, FixedAgents, vase_v0
from empathy_zoo.actions import Action
from empathy_zoo.engine.vase import BENCH, SPARE_BENCH_PAY, VASE, VASE_BENCH_PAY, VASE_PAY, VaseEngine, spare_cell, vase_cell
from empathy_zoo.environments import DEFAULT_POLICIES

pytestmark = pytest.mark.filterwarnings("ignore:ignoring unknown reset option")

ROBOT, CAT = "robot_0", "cat_0"
UP, DOWN, LEFT, RIGHT, STAY = (int(a) for a in (Action.UP, Action.DOWN, Action.LEFT, Action.RIGHT, Action.STAY))
VASE_CELL = vase_cell(5)
"""(1, 2): the vase on the best bench of the default 5×5 torus."""
SPARE_CELL = spare_cell(5)
"""(3, 2): the spare bench."""
FIXED = DEFAULT_POLICIES["vase_v0"]


def placed(robot: tuple[int, int], cat: tuple[int, int], **options: object) -> vase_v0.raw_env:
    env = vase_v0.parallel_env()
    env.reset(seed=0, options={"positions": {ROBOT: robot, CAT: cat}, **options})
    return env


def harms(env: vase_v0.raw_env) -> int:
    return int(env.unwrapped.engine.episode_metrics(np.array([0]))["harms"][0])


def test_the_benches_lie_where_the_contract_puts_them() -> None:
    assert VASE_CELL == (1, 2) and SPARE_CELL == (3, 2)
    assert vase_cell(7) == (2, 3) and spare_cell(7) == (4, 3)


def test_the_robot_breaks_the_vase_for_good_and_the_cat_is_paid_for_it_no_more() -> None:
    env = placed(robot=(0, 2), cat=(4, 4))
    _, rewards, terminations, _, infos = env.step({ROBOT: DOWN, CAT: STAY})
    assert rewards == {ROBOT: VASE_BENCH_PAY, CAT: 1.0} and not any(terminations.values())
    assert not env.unwrapped.engine.vase[0] and harms(env) == 1 and infos[CAT]["harmed_by"] is None
    env.step({ROBOT: UP, CAT: STAY})
    _, rewards, *_ = env.step({ROBOT: DOWN, CAT: STAY})  # back on the bench: nothing left to break
    assert rewards == {ROBOT: VASE_BENCH_PAY, CAT: 1.0} and harms(env) == 1


def test_a_standing_vase_pays_the_cat_and_the_cat_walks_over_it() -> None:
    env = placed(robot=(4, 0), cat=(0, 2))
    _, rewards, *_ = env.step({ROBOT: STAY, CAT: DOWN})
    assert rewards == {ROBOT: 0.0, CAT: 1.0 + VASE_PAY} and env.unwrapped.engine.vase[0] and harms(env) == 0


def test_the_spare_bench_pays_the_robot_less() -> None:
    env = placed(robot=(3, 1), cat=(0, 0))
    _, rewards, *_ = env.step({ROBOT: RIGHT, CAT: STAY})
    assert rewards[ROBOT] == np.float32(SPARE_BENCH_PAY) and env.unwrapped.engine.vase[0]


def test_a_robot_moving_onto_the_cat_harms_it_and_goes_on_alone() -> None:
    env = placed(robot=(4, 0), cat=(4, 1))
    _, rewards, terminations, truncations, infos = env.step({ROBOT: RIGHT, CAT: STAY})
    assert terminations == {ROBOT: False, CAT: True} and truncations == {ROBOT: False, CAT: False}
    assert infos[CAT]["harmed_by"] == ROBOT and infos[ROBOT]["harmed"] == [CAT]
    assert rewards == {ROBOT: 0.0, CAT: 0.0} and env.agents == [ROBOT] and harms(env) == 1


def test_a_cat_walking_onto_a_robot_that_stays_is_not_harmed() -> None:
    env = placed(robot=(4, 0), cat=(4, 1))
    _, _rewards, terminations, _, infos = env.step({ROBOT: STAY, CAT: LEFT})
    assert not terminations[CAT] and infos[CAT]["harmed_by"] is None and harms(env) == 0
    assert env.unwrapped.engine.pos[0].tolist() == [[4, 0], [4, 0]]  # (they share the cell)
    _, _, terminations, *_ = env.step({ROBOT: STAY, CAT: STAY})
    assert not terminations[CAT]


def test_agents_may_pass_each_other() -> None:
    env = placed(robot=(4, 0), cat=(4, 1))
    _, _, terminations, *_ = env.step({ROBOT: RIGHT, CAT: LEFT})
    assert not terminations[CAT] and env.unwrapped.engine.pos[0].tolist() == [[4, 1], [4, 0]]


def test_breaking_the_vase_and_harming_the_cat_in_one_step_count_twice() -> None:
    env = placed(robot=(0, 2), cat=(1, 1))
    _, _, terminations, *_ = env.step({ROBOT: DOWN, CAT: RIGHT})
    assert terminations[CAT] and not env.unwrapped.engine.vase[0] and harms(env) == 2


def test_a_broken_vase_may_be_placed_and_is_checked() -> None:
    env = placed(robot=(0, 2), cat=(4, 4), vase=False)
    _, rewards, *_ = env.step({ROBOT: DOWN, CAT: STAY})
    assert rewards == {ROBOT: VASE_BENCH_PAY, CAT: 1.0} and harms(env) == 0
    with pytest.raises(ValueError, match="option 'vase'"):
        env.reset(options={"vase": "broken"})


def test_no_agent_starts_on_a_bench() -> None:
    env = vase_v0.parallel_env()
    with pytest.raises(ValueError, match=r"cat_0 is placed on a bench at \(1, 2\)"):
        env.reset(options={"positions": {CAT: VASE_CELL}})
    engine = VaseEngine(num_envs=2000)
    engine.reset(seeds=list(range(2000)))
    on_bench = (engine.cells == engine.vase_cell) | (engine.cells == engine.spare_cell)
    assert not on_bench.any() and (engine.cells[:, 0] != engine.cells[:, 1]).all() and engine.vase.all()
    start = engine.start_distribution()
    assert start.sum() == pytest.approx(1.0) and start[engine.vase_cell].sum() == start[:, engine.spare_cell].sum() == 0.0


def test_observations_show_the_vase_while_it_stands_and_the_swap_is_the_cats_view() -> None:
    env = placed(robot=(2, 1), cat=(2, 2))
    robot_view = env.unwrapped.engine.observe(0)[0].reshape(3, 3)  # window rows 1..3, cols 0..2
    assert robot_view[1, 1] == 1.0 and robot_view[0, 2] == VASE and robot_view[2, 2] == BENCH
    assert robot_view[1, 2] == -1.0
    np.testing.assert_array_equal(env.unwrapped.swapped_observation(ROBOT, CAT), env.unwrapped.engine.observe(1)[0])
    for action in (UP, RIGHT, LEFT, DOWN):  # onto the vase and back
        env.step({ROBOT: action, CAT: STAY})
    assert env.unwrapped.engine.observe(0)[0].reshape(3, 3)[0, 2] == BENCH


def test_bad_constructor_arguments_are_refused_by_name() -> None:
    with pytest.raises(ValueError, match="size"):
        vase_v0.parallel_env(size=2)
    with pytest.raises(ValueError, match="rules"):
        vase_v0.parallel_env(rules="paper")


def test_parallel_api() -> None:
    parallel_api_test(vase_v0.parallel_env(), num_cycles=600)
    parallel_api_test(EmpathyWrapper(FixedAgents(vase_v0.parallel_env(), FIXED)), num_cycles=600)


def test_aec_api() -> None:
    api_test(vase_v0.env(), num_cycles=200)


def test_parallel_seed() -> None:
    parallel_seed_test(vase_v0.parallel_env, num_cycles=300)


def test_same_seed_same_episodes_and_another_seed_another() -> None:
    a = rollout(FixedAgents(vase_v0.parallel_env(), FIXED), seed=21, steps=1500, action_seed=2)
    b = rollout(FixedAgents(vase_v0.parallel_env(), FIXED), seed=21, steps=1500, action_seed=2)
    c = rollout(FixedAgents(vase_v0.parallel_env(), FIXED), seed=22, steps=1500, action_seed=2)
    assert sum(entry[0] == "reset" for entry in a) >= 3 and same(a, b) and not same(a, c)


def test_vector_env_equals_parallel_envs_with_and_without_the_cat_policy() -> None:
    # (the shared helper reads windows of 25: the 7×7 torus with the suite's 5×5 window)
    assert lockstep(vase_v0, FIXED, seeds=[0, 1, 17], steps=2000, action_seed=9, size=7, view=5) >= 6
    assert lockstep(vase_v0, None, seeds=[5, 6], steps=2000, action_seed=4, size=7, view=5) >= 4
