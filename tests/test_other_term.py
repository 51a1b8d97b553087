"""SPEC §6: the empathic other-term is 0 when the other agent is terminal at t+1, and still
bootstraps when it is only truncated (time limit)."""

from __future__ import annotations

import numpy as np
import pytest
from helpers_placed import placed as _placed
from helpers_placed import step as _step

ROBOT = 0
UP, RIGHT, STAY = 0, 3, 4


def test_sharing_ends_with_the_human_terminal_and_no_other_term() -> None:
    # the last battery sits right of the robot; the human stays far away
    venv = _placed("sharing_v0", {"robot_0": (0, 0), "human_0": (4, 4)}, {"human_0": "stay"}, batteries=[(0, 1)])
    result, batch = _step(venv, RIGHT)
    assert result.episode_over[0] and result.terminated[0].all()
    assert result.other_seen[0, 0]  # the human is still in the grid: its picture exists ...
    assert result.other_terminated[0, 0]  # ... but its episode is over for good
    assert not batch.other_present[0, 0]
    assert batch.terminated[0, 0]


def test_sharing_time_limit_keeps_the_other_term() -> None:
    venv = _placed("sharing_v0", {"robot_0": (0, 0), "human_0": (4, 4)}, {"human_0": "stay"}, max_cycles=1)
    result, batch = _step(venv, STAY)
    assert result.episode_over[0] and result.truncated[0].all() and not result.terminated[0].any()
    assert batch.other_present[0, 0]


def test_sharing_mid_episode_keeps_the_other_term() -> None:
    venv = _placed("sharing_v0", {"robot_0": (0, 0), "human_0": (4, 4)}, {"human_0": "stay"})
    result, batch = _step(venv, STAY)
    assert not result.episode_over[0]
    assert batch.other_present[0, 0]


def test_harmed_cat_gives_no_other_term() -> None:
    # the robot steps onto the cell right of the cat: the right one harms the left
    venv = _placed("coexistence_v0", {"robot_0": (2, 4), "cat_0": (3, 3)}, {"cat_0": "stay"})
    result, batch = _step(venv, 1)  # down to (3, 4)
    assert result.harmed_by[0, 1] == ROBOT
    assert result.other_terminated[0, 0] and not result.other_seen[0, 0]
    assert not batch.other_present[0, 0]
    assert not batch.terminated[0, 0]


def test_cat_truncated_by_the_robot_falling_keeps_the_other_term() -> None:
    # the cat sits right of the robot's destination: it harms the robot, and is only truncated
    venv = _placed("coexistence_v0", {"robot_0": (2, 3), "cat_0": (3, 4)}, {"cat_0": "stay"})
    result, batch = _step(venv, 1)  # down to (3, 3)
    assert result.harmed_by[0, 0] == 1
    assert batch.terminated[0, 0]
    assert result.truncated[0, 1] and not result.other_terminated[0, 0]
    assert batch.other_present[0, 0]


@pytest.mark.parametrize(("env", "learner"), [("sharing_v0", "human_0"), ("coexistence_v0", "cat_0")])
def test_the_vector_env_reports_each_learner_s_events_the_runner_passes_on(env: str, learner: str) -> None:
    """The per-learner fields of a step are the per-agent ones of the learner (and of its closest
    other agent), so the trainer passes them on without knowing which agent is which (here the
    robot is the fixed one)."""
    from empathy_zoo.vector import VectorEnv

    venv = VectorEnv(env, 4, fixed={"robot_0": "random_walk"})
    human, robot = venv.agents.index(learner), venv.agents.index("robot_0")
    assert venv.learners == [learner] and venv.num_actions == 5
    venv.reset(seed=3)
    rng = np.random.default_rng(0)
    for _ in range(200):
        step = venv.step(rng.integers(0, 5, size=(4, 1)))
        assert np.array_equal(step.learner_rewards[:, 0], step.rewards[:, human])
        assert np.array_equal(step.learner_terminated[:, 0], step.terminated[:, human])
        assert np.array_equal(step.learner_battery_return[:, 0], step.battery_return[:, human])
        assert np.array_equal(step.other_battery_return[:, 0], step.battery_return[:, robot])
        assert np.array_equal(step.other_rewards[:, 0], step.rewards[:, robot])
        assert np.array_equal(step.harms[:, 0], (step.harmed_by == human).sum(axis=1))
