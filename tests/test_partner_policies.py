"""The partners of held-out evaluation (empathy_zoo.partner_policies): exact moves from hand-made
contexts and windows, the slow walk's rate and its batched path, and each one driving the PettingZoo
env and the vector env alike."""

from __future__ import annotations

import numpy as np
import pytest

from empathy_zoo import ENVIRONMENTS, FixedAgents
from empathy_zoo.actions import Action
from empathy_zoo.partner_policies import BATTERY_VALUE, Chase, KeepAway, NearestBattery, SlowWalk
from empathy_zoo.policies import POLICIES, batched, make_policy
from empathy_zoo.vector import VectorEnv

SIZE = 7


def context(cat: tuple[int, int], robot: tuple[int, int] | None, step: int = 0) -> dict:
    positions = {"cat_0": cat, **({"robot_0": robot} if robot is not None else {})}
    return {"step": step, "agent": "cat_0", "size": SIZE, "positions": positions}


@pytest.mark.parametrize(
    "name, cls", [("slow_walk", SlowWalk), ("chase", Chase), ("keep_away", KeepAway), ("nearest_battery", NearestBattery)]
)
def test_registered_by_name(name: str, cls: type) -> None:
    assert POLICIES[name] is cls and isinstance(make_policy(name), cls)


@pytest.mark.parametrize(
    "robot, action",
    [
        ((2, 0), Action.DOWN),
        ((5, 0), Action.UP),
        ((0, 3), Action.RIGHT),
        ((0, 5), Action.LEFT),
        ((3, 3), Action.DOWN),
        ((0, 0), Action.STAY),
    ],
)
def test_chase_steps_the_shorter_way_round_rows_first(robot, action) -> None:
    assert Chase().act(np.zeros(25, np.float32), context((0, 0), robot)) == action


def test_chase_rests_between_its_steps_and_when_the_robot_is_gone() -> None:
    every_other = Chase(every=2)
    assert every_other.act(np.zeros(25), context((0, 0), (2, 0), step=1)) == Action.STAY
    assert every_other.act(np.zeros(25), context((0, 0), (2, 0), step=2)) == Action.DOWN
    assert Chase().act(np.zeros(25), context((0, 0), None)) == Action.STAY


@pytest.mark.parametrize(
    "cat, robot, action",
    [
        ((3, 3), (2, 3), Action.DOWN),  # robot above: only down leaves it 2 away
        ((3, 3), (3, 2), Action.UP),  # robot on the left: up, down and right reach 2; up comes first
        ((0, 0), (3, 3), Action.UP),  # as far as a 7×7 torus allows (6): up keeps 6 and comes first
    ],
)
def test_keep_away_takes_the_farthest_move_first_in_action_order(cat, robot, action) -> None:
    assert KeepAway().act(np.zeros(25), context(cat, robot)) == action


def window(*cells: tuple[int, int]) -> np.ndarray:
    """A 5×5 Sharing window with batteries at ``(row, col)`` offsets from its centre."""
    picture = np.zeros((5, 5), np.float32)
    picture[2, 2] = 1.0  # itself
    for row, col in cells:
        picture[2 + row, 2 + col] = BATTERY_VALUE
    return picture.ravel()


@pytest.mark.parametrize(
    "cells, action",
    [
        ([(-2, 0), (0, 2)], Action.UP),  # two at distance 2: the first in row-major order
        ([(1, -1)], Action.DOWN),  # rows first
        ([(0, -1), (2, 2)], Action.LEFT),
        ([(0, 2), (-1, -2)], Action.RIGHT),
    ],
)
def test_nearest_battery_heads_for_the_nearest_it_sees(cells, action) -> None:
    assert NearestBattery().act(window(*cells), {"step": 3}) == action


def test_nearest_battery_patrols_when_it_sees_none() -> None:
    human = NearestBattery()
    assert [human.act(window(), {"step": t}) for t in range(8)] == [Action.UP] + [Action.RIGHT] * 6 + [Action.UP]
    with pytest.raises(ValueError, match="square window"):
        human.act(np.zeros(24), {"step": 0})


def test_slow_walk_moves_about_as_often_as_it_says() -> None:
    walk = SlowWalk(move_probability=0.1)
    walk.reset(seed=3)
    actions = np.array([walk.act(np.zeros(25), {}) for _ in range(20_000)])
    moves = actions != Action.STAY
    assert 0.09 < moves.mean() < 0.11
    assert set(np.unique(actions[moves])) == {Action.UP, Action.DOWN, Action.LEFT, Action.RIGHT}


def test_slow_walk_batched_gives_each_environment_its_own_walk() -> None:
    seeds = [5, 9, 5]
    fast = batched(SlowWalk(0.3), len(seeds))
    fast.reset(np.arange(len(seeds)), seeds)
    active = np.array([True, True, False])
    alone = []
    for seed in seeds[:2]:
        walk = SlowWalk(0.3)
        walk.reset(seed=seed)
        alone.append([walk.act(np.zeros(25), {}) for _ in range(50)])
    together = np.array([fast.act(None, np.arange(3), active) for _ in range(50)])
    assert together[:, 0].tolist() == alone[0] and together[:, 1].tolist() == alone[1]
    assert fast.state()["counts"].tolist() == [50, 50, 0]  # an absent agent's stream stays put


def test_slow_walk_resumes_from_its_state() -> None:
    walk = SlowWalk(0.5)
    walk.reset(seed=1)
    [walk.act(np.zeros(25), {}) for _ in range(7)]
    copy = SlowWalk(0.5)
    copy.load_state(walk.state())
    assert [walk.act(np.zeros(25), {}) for _ in range(20)] == [copy.act(np.zeros(25), {}) for _ in range(20)]


@pytest.mark.parametrize("bad", [0.0, 1.5, -0.1, True, "often"])
def test_slow_walk_refuses_a_probability_outside_0_1(bad) -> None:
    with pytest.raises(ValueError, match="move_probability"):
        SlowWalk(bad)


@pytest.mark.parametrize("bad", [{"every": 0}, {"target": ""}])
def test_chase_refuses_bad_arguments(bad) -> None:
    with pytest.raises(ValueError):
        Chase(**bad)


@pytest.mark.parametrize(
    "env, agent, policy",
    [
        ("coexistence_v0", "cat_0", "slow_walk"),
        ("coexistence_v0", "cat_0", "chase"),
        ("coexistence_v0", "cat_0", "keep_away"),
        ("sharing_v0", "human_0", "nearest_battery"),
        ("coexistence_v0", "cat_0", {"policy": "noisy", "partner": "chase", "noise": 0.3}),
        ("coexistence_v0", "cat_0", {"policy": "population", "members": ["chase", "random_walk"]}),
    ],
)
@pytest.mark.parametrize("seed", [0, 7])
def test_each_partner_drives_the_pettingzoo_env_and_the_vector_env_alike(env, agent, policy, seed) -> None:
    fixed = {agent: policy}
    parallel = FixedAgents(ENVIRONMENTS[env].parallel_env(max_cycles=80), fixed)
    vector = VectorEnv(env, 1, fixed=fixed, max_cycles=80)
    observations, _ = parallel.reset(seed=seed)
    vector_obs = vector.reset(seed=[seed])
    actions = np.random.default_rng(seed).integers(0, 5, size=80)
    for action in actions:
        assert np.array_equal(observations["robot_0"], vector_obs[0, 0])
        observations, _, _, _, _ = parallel.step({"robot_0": int(action)})
        step = vector.step(np.array([[action]]))
        vector_obs = step.final_observations
        if not parallel.agents:
            assert step.finished["env"].tolist() == [0]
            return
