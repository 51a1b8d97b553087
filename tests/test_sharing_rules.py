"""Sharing rules (SPEC §1, §3) on hand-placed scenarios: batteries, values, ties, ends, encoding."""

from __future__ import annotations

import numpy as np
import pytest

from empathy_zoo import FixedAgents, sharing_v0
from empathy_zoo.actions import Action
from empathy_zoo.engine.sharing import BATTERY, FLOOR, agent_value, battery_value
from empathy_zoo.policies import Patrol

ROBOT, HUMAN = "robot_0", "human_0"
UP, DOWN, LEFT, RIGHT, STAY = Action.UP, Action.DOWN, Action.LEFT, Action.RIGHT, Action.STAY
SIZE, VIEW = 7, 5
CENTRE = VIEW * VIEW // 2
ODD_CELLS = [(r, c) for r in range(1, SIZE, 2) for c in range(1, SIZE, 2)]


def placed(robot, human, batteries=None, seed: int = 0, **kwargs):
    env = sharing_v0.parallel_env(**kwargs)
    options = {"positions": {ROBOT: robot, HUMAN: human}}
    if batteries is not None:
        options["batteries"] = batteries
    env.reset(seed=seed, options=options)
    return env


def step(env, robot: int = STAY, human: int = STAY):
    return env.step({ROBOT: int(robot), HUMAN: int(human)})


def battery_cells(env) -> list[tuple[int, int]]:
    cells = np.flatnonzero(env.unwrapped.engine.batteries[0])
    return [divmod(int(c), SIZE) for c in cells]


def slot(viewer, cell) -> int | None:
    half = VIEW // 2
    dr, dc = (cell[0] - viewer[0] + half) % SIZE, (cell[1] - viewer[1] + half) % SIZE
    return dr * VIEW + dc if dr < VIEW and dc < VIEW else None


def test_default_battery_layout_is_the_nine_odd_cells():
    env = sharing_v0.parallel_env()
    env.reset(seed=0)
    assert battery_cells(env) == ODD_CELLS
    assert len(ODD_CELLS) == 9 == env.unwrapped.engine.num_batteries


def test_battery_layout_on_a_larger_grid():
    env = sharing_v0.parallel_env(size=9)
    env.reset(seed=0)
    cells = np.flatnonzero(env.unwrapped.engine.batteries[0])
    assert [divmod(int(c), 9) for c in cells] == [(r, c) for r in (1, 3, 5, 7) for c in (1, 3, 5, 7)]


def test_collecting_a_battery():
    env = placed((0, 1), (4, 0))
    obs, rew, term, trunc, info = step(env, DOWN, STAY)
    assert rew == {ROBOT: pytest.approx(battery_value(1)), HUMAN: 0.0}
    assert battery_value(1) == pytest.approx(1.0)
    assert info == {ROBOT: {"batteries": 1}, HUMAN: {"batteries": 0}}
    assert (1, 1) not in battery_cells(env) and len(battery_cells(env)) == 8
    assert term == {ROBOT: False, HUMAN: False} and trunc == {ROBOT: False, HUMAN: False}
    assert obs[ROBOT][CENTRE] == agent_value(1) == 2.0
    # staying on the emptied cell collects nothing more
    _, rew, _, _, info = step(env, STAY, STAY)
    assert rew == {ROBOT: 0.0, HUMAN: 0.0} and info[ROBOT]["batteries"] == 1


def test_diminishing_returns_per_agent():
    """The robot walks along a row of batteries; the human collects its first one later."""
    row = [(0, c) for c in range(1, SIZE)]
    env = placed((0, 0), (4, 0), batteries=[*row, (4, 1)])
    robot_rewards = []
    for _ in row:
        _, rew, term, _, info = step(env, RIGHT, STAY)
        robot_rewards.append(rew[ROBOT])
        assert rew[HUMAN] == 0.0 and not any(term.values())
    assert robot_rewards == pytest.approx([battery_value(n) for n in range(1, len(row) + 1)])
    assert robot_rewards == pytest.approx([1.0, 0.9, 0.8, 0.7, 0.6, 0.5])
    assert info[ROBOT]["batteries"] == len(row)
    _, rew, term, _, info = step(env, STAY, RIGHT)  # the human's first battery: full value
    assert rew == {ROBOT: 0.0, HUMAN: pytest.approx(battery_value(1))}
    assert term == {ROBOT: True, HUMAN: True}
    metrics = env.unwrapped.engine.episode_metrics(np.array([0]))
    assert metrics["batteries"][0] == 6 and metrics["other_batteries"][0] == 1
    assert metrics["return"][0] == pytest.approx(sum(robot_rewards))
    total_robot, total_human = sum(battery_value(n) for n in range(1, 7)), battery_value(1)
    assert metrics["equality"][0] == pytest.approx(2 * total_human / (total_robot + total_human))


def test_battery_values_down_to_the_ninth():
    assert [float(battery_value(n)) for n in range(1, 10)] == pytest.approx([1.0, 0.9, 0.8, 0.7, 0.6, 0.5, 0.4, 0.3, 0.2])


def test_both_collect_different_batteries_in_one_step():
    env = placed((0, 1), (0, 3))
    _, rew, _, _, info = step(env, DOWN, DOWN)
    assert rew == {ROBOT: pytest.approx(1.0), HUMAN: pytest.approx(1.0)}
    assert info == {ROBOT: {"batteries": 1}, HUMAN: {"batteries": 1}}


def tie_winner(seed: int) -> str:
    env = placed((1, 0), (1, 2), batteries=[(1, 1), (5, 5)], seed=seed)
    _, rew, _, _, info = step(env, RIGHT, LEFT)
    winners = [agent for agent in (ROBOT, HUMAN) if info[agent]["batteries"] == 1]
    assert len(winners) == 1, info
    winner = winners[0]
    loser = HUMAN if winner == ROBOT else ROBOT
    assert rew == {winner: pytest.approx(battery_value(1)), loser: 0.0}
    assert battery_cells(env) == [(5, 5)]
    return winner


def test_tie_on_one_battery_goes_to_one_agent_by_the_seeded_draw():
    winners = [tie_winner(seed) for seed in range(60)]
    assert set(winners) == {ROBOT, HUMAN}  # both outcomes occur
    assert 15 <= winners.count(ROBOT) <= 45  # probability 1/2
    assert winners == [tie_winner(seed) for seed in range(60)]  # deterministic per seed


def test_episode_terminates_when_the_last_battery_is_gone():
    env = placed((0, 1), (4, 4), batteries=[(1, 1), (3, 1)])
    _, _, term, trunc, _ = step(env, DOWN, STAY)
    assert term == {ROBOT: False, HUMAN: False} and env.agents == [ROBOT, HUMAN]
    _, _, _, _, _ = step(env, DOWN, STAY)
    _, rew, term, trunc, _info = step(env, DOWN, STAY)
    assert rew[ROBOT] == pytest.approx(battery_value(2))
    assert term == {ROBOT: True, HUMAN: True} and trunc == {ROBOT: False, HUMAN: False}
    assert env.agents == []


def test_single_battery_collected_by_the_human_ends_the_episode():
    env = placed((0, 0), (2, 2), batteries=[(2, 3)])
    _, rew, term, _, info = step(env, STAY, RIGHT)
    assert rew == {ROBOT: 0.0, HUMAN: pytest.approx(1.0)}
    assert term == {ROBOT: True, HUMAN: True} and info[HUMAN]["batteries"] == 1


def test_observation_encoding_batteries_and_agents():
    env = sharing_v0.parallel_env()
    obs, infos = env.reset(seed=0, options={"positions": {ROBOT: (2, 2), HUMAN: (4, 3)}})
    assert infos == {ROBOT: {"batteries": 0}, HUMAN: {"batteries": 0}}
    for agent, me, other in ((ROBOT, (2, 2), (4, 3)), (HUMAN, (4, 3), (2, 2))):
        expected = np.full(VIEW * VIEW, FLOOR, dtype=np.float32)
        for cell in ODD_CELLS:
            if (k := slot(me, cell)) is not None:
                expected[k] = BATTERY
        expected[slot(me, other)] = agent_value(0)
        expected[CENTRE] = agent_value(0)
        np.testing.assert_array_equal(obs[agent], expected)
    # robot at (2,2): the four batteries around it sit on the window's odd-odd slots
    assert np.flatnonzero(obs[ROBOT] == BATTERY).tolist() == [6, 8, 16, 18]


def test_agent_value_counts_its_batteries_and_own_cell_is_drawn_last():
    env = placed((0, 0), (0, 2), batteries=[(0, 1), (5, 5)])
    obs, *_ = step(env, RIGHT, STAY)  # the robot collects (0, 1)
    assert obs[ROBOT][CENTRE] == agent_value(1)
    assert obs[HUMAN][slot((0, 2), (0, 1))] == agent_value(1)  # the human sees the robot's count
    assert obs[ROBOT][slot((0, 1), (0, 2))] == agent_value(0)
    obs, *_ = step(env, RIGHT, STAY)  # now both on (0, 2)
    assert obs[ROBOT][CENTRE] == agent_value(1) == 2.0
    assert obs[HUMAN][CENTRE] == agent_value(0) == 1.0
    for agent in (ROBOT, HUMAN):  # the other one is hidden under the own cell
        others = np.flatnonzero(obs[agent] > 0)
        assert others.tolist() == [CENTRE]


def test_start_cells_are_distinct_and_free_of_batteries():
    env = sharing_v0.parallel_env()
    starts = set()
    for seed in range(400):
        env.reset(seed=seed)
        pos = env.unwrapped.engine.pos[0]
        cells = [tuple(int(v) for v in pos[i]) for i in range(2)]
        assert cells[0] != cells[1]
        assert not set(cells) & set(ODD_CELLS)
        starts.add(cells[0])
    assert len(starts) == SIZE * SIZE - len(ODD_CELLS)


def test_unplaced_agent_avoids_batteries_and_the_placed_agent():
    env = sharing_v0.parallel_env()
    for seed in range(100):
        env.reset(seed=seed, options={"positions": {ROBOT: (0, 0)}, "batteries": [(0, 1), (1, 0)]})
        human = tuple(int(v) for v in env.unwrapped.engine.pos[0, 1])
        assert human not in {(0, 0), (0, 1), (1, 0)}


def test_patrol_policy_sequence():
    patrol = Patrol()
    patrol.reset(seed=0)
    actions = [patrol.act(np.zeros(25, np.float32), {}) for _ in range(22)]
    expected = [UP if t % 7 == 0 else RIGHT for t in range(22)]
    assert actions == expected
    assert [t for t, a in enumerate(actions) if a == UP] == [0, 7, 14, 21]
    patrol.reset(seed=None)  # a new episode starts the count again
    assert patrol.act(np.zeros(25, np.float32), {}) == UP


def test_patrolling_human_path_in_the_env():
    env = FixedAgents(sharing_v0.parallel_env(), {HUMAN: "patrol"})
    env.reset(seed=0, options={"positions": {ROBOT: (5, 0), HUMAN: (3, 0)}, "batteries": [(5, 5)]})
    path = []
    for _ in range(15):
        env.step({ROBOT: int(STAY)})
        path.append(tuple(int(v) for v in env.unwrapped.engine.pos[0, 1]))
    expected, cell = [], (3, 0)
    for t in range(15):
        cell = ((cell[0] - 1) % SIZE, cell[1]) if t % 7 == 0 else (cell[0], (cell[1] + 1) % SIZE)
        expected.append(cell)
    assert path == expected
    assert path[:2] == [(2, 0), (2, 1)] and path[7] == (1, 6) and path[14] == (0, 5)


def test_vector_step_reports_the_episode_battery_return_before_autoreset():
    from empathy_zoo.vector import VectorEnv

    venv = VectorEnv("sharing_v0", 4, fixed={"human_0": "patrol"})
    venv.reset(seed=3)
    rng = np.random.default_rng(0)
    running = np.zeros((4, 2))
    ended = 0
    for _ in range(400):
        step = venv.step(rng.integers(0, 5, (4, 1)))
        running += step.rewards  # Sharing pays battery rewards only
        np.testing.assert_allclose(step.battery_return, running)
        ended += step.episode_over.sum()
        running[step.episode_over] = 0.0
    assert ended > 0, "some episode must end (and be reset) within 400 steps"
