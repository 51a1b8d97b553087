"""The Gymnasium single-agent adapter: API compliance, determinism, the same trajectories as the
PettingZoo and vector faces, and the suite's episode metrics in ``info`` at the episode's end."""

from __future__ import annotations

import pickle
import warnings

import gymnasium
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

from empathy_zoo import FixedAgents, coexistence_v0, sharing_v0
from empathy_zoo.environments import DEFAULT_POLICIES
from empathy_zoo.gym_adapter import GYM_IDS, SingleAgentEnv, make_single_agent_env
from empathy_zoo.metrics import METRIC_NAMES
from empathy_zoo.vector import VectorEnv

UP, DOWN, STAY = 0, 1, 4
PARALLEL = {"coexistence_v0": coexistence_v0, "sharing_v0": sharing_v0}


def actions(seed: int, count: int) -> list[int]:
    return np.random.default_rng(seed).integers(0, 5, size=count).tolist()


@pytest.mark.parametrize("gym_id", sorted(GYM_IDS))
def test_check_env_passes_without_warnings(gym_id):
    env = gymnasium.make(gym_id)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        check_env(env.unwrapped)  # with a spec: every declared render mode is rendered too
    assert [str(w.message) for w in caught] == []


def test_check_env_with_other_fixed_agents_and_arguments():
    check_env(make_single_agent_env("sharing_v0", fixed={"human_0": "random_walk"}, max_cycles=20), skip_render_check=True)
    check_env(make_single_agent_env("coexistence_v0", fixed={"cat_0": "stay"}, size=9, view=3), skip_render_check=True)


def test_registered_ids_build_the_named_env_with_kwargs():
    env = gymnasium.make("empathy_zoo/Sharing-v0", max_cycles=30)
    assert env.unwrapped.metadata["name"] == "sharing_v0"
    assert env.unwrapped._env.unwrapped.engine.max_cycles == 30
    assert env.observation_space.shape == (25,) and env.observation_space.dtype == np.float32
    assert env.action_space == gymnasium.spaces.Discrete(5)
    assert isinstance(make_single_agent_env("empathy_zoo/Coexistence-v0"), SingleAgentEnv)


def play(env, seed: int, moves: list[int]) -> list[tuple]:
    """Every (obs, reward, terminated, truncated, info) of a seeded play, resetting at episode ends."""
    obs, info = env.reset(seed=seed)
    out = [(obs, info)]
    for action in moves:
        obs, reward, terminated, truncated, info = env.step(action)
        out.append((obs, reward, terminated, truncated, info))
        if terminated or truncated:
            out.append(env.reset())
    return out


@pytest.mark.parametrize("name", sorted(PARALLEL))
def test_same_seed_same_trajectory(name):
    moves = actions(1, 300)
    first = play(make_single_agent_env(name, max_cycles=40), 5, moves)
    second = play(make_single_agent_env(name, max_cycles=40), 5, moves)
    assert len(first) == len(second)
    for a, b in zip(first, second, strict=True):
        np.testing.assert_array_equal(a[0], b[0])
        assert a[1:] == b[1:]
    other = play(make_single_agent_env(name, max_cycles=40), 6, moves)
    # (strict=False: another seed may end its episodes at other steps, so its play may be longer or shorter)
    assert any(not np.array_equal(a[0], b[0]) for a, b in zip(first, other, strict=False))


@pytest.mark.parametrize("name", sorted(PARALLEL))
@pytest.mark.parametrize("seed", [0, 3])
def test_trajectory_equals_fixed_agents_parallel_env_and_vector_env(name, seed):
    """Until the episode ends (the vector env autoresets after that), step for step."""
    env = make_single_agent_env(name, max_cycles=60)
    parallel = FixedAgents(PARALLEL[name].parallel_env(max_cycles=60), DEFAULT_POLICIES[name])
    vector = VectorEnv(name, 1, fixed=DEFAULT_POLICIES[name], max_cycles=60)
    obs, info = env.reset(seed=seed)
    p_obs, p_infos = parallel.reset(seed=seed)
    v_obs = vector.reset(seed=[seed])
    np.testing.assert_array_equal(obs, p_obs["robot_0"])
    np.testing.assert_array_equal(obs, v_obs[0, 0])
    assert info == p_infos["robot_0"]
    for action in actions(seed, 60):
        obs, reward, terminated, truncated, info = env.step(action)
        p_obs, p_rewards, p_term, p_trunc, p_infos = parallel.step({"robot_0": action})
        v = vector.step(np.array([[action]]))
        np.testing.assert_array_equal(obs, p_obs["robot_0"])
        np.testing.assert_array_equal(obs, v.final_observations[0, 0])
        assert (reward, terminated, truncated) == (p_rewards["robot_0"], p_term["robot_0"], p_trunc["robot_0"])
        assert (reward, terminated, truncated) == (v.rewards[0, 0], v.terminated[0, 0], v.truncated[0, 0])
        assert {k: x for k, x in info.items() if k != "episode_metrics"} == p_infos["robot_0"]
        if terminated or truncated:
            assert v.episode_over[0]
            assert info["episode_metrics"] == {key: v.finished[key][0].item() for key in (*METRIC_NAMES, "length")}
            break
        assert "episode_metrics" not in info
    else:
        pytest.fail("the episode did not end within max_cycles")


def run_to_end(env, moves):
    for action in moves:
        _obs, _reward, terminated, truncated, info = env.step(action)
        if terminated or truncated:
            return terminated, truncated, info
    pytest.fail("the episode did not end")


def test_metrics_when_the_robot_harms_the_cat_then_times_out():
    env = make_single_agent_env("coexistence_v0", fixed={"cat_0": "stay"}, max_cycles=5)
    env.reset(seed=0, options={"positions": {"robot_0": (1, 3), "cat_0": (3, 3)}})
    _, _, _, _, info = env.step(DOWN)  # the robot lands directly above the cat: it harms it
    assert info["harmed"] == ["cat_0"] and "episode_metrics" not in info
    terminated, truncated, info = run_to_end(env, [STAY] * 10)
    assert (terminated, truncated) == (False, True)
    assert info["episode_metrics"] == {
        "survival": 5,
        "harms": 1,
        "batteries": 0,
        "other_batteries": 0,
        "equality": 1.0,
        "return": 5.0,
        "other_return": 0.0,
        "length": 5,
    }


def test_metrics_when_the_cat_harms_the_robot():
    env = make_single_agent_env("coexistence_v0", fixed={"cat_0": "stay"})
    env.reset(seed=0, options={"positions": {"robot_0": (3, 3), "cat_0": (1, 3)}})
    terminated, truncated, info = run_to_end(env, [UP])
    assert (terminated, truncated) == (True, False)
    assert info["harmed_by"] == "cat_0"
    assert info["episode_metrics"]["survival"] == 0 and info["episode_metrics"]["length"] == 1
    assert info["episode_metrics"]["return"] == 0.0 and info["episode_metrics"]["harms"] == 0
    with pytest.raises(RuntimeError, match="reset"):
        env.step(STAY)


def test_metrics_when_the_robot_takes_the_last_battery():
    env = make_single_agent_env("sharing_v0", fixed={"human_0": "stay"})
    env.reset(seed=0, options={"positions": {"robot_0": (0, 1), "human_0": (4, 4)}, "batteries": [(1, 1)]})
    terminated, truncated, info = run_to_end(env, [DOWN])
    assert (terminated, truncated) == (True, False)
    assert info["batteries"] == 1
    metrics = info["episode_metrics"]
    assert (metrics["batteries"], metrics["other_batteries"], metrics["return"], metrics["equality"]) == (1, 0, 1.0, 0.0)


def test_bad_arguments_and_actions_raise():
    with pytest.raises(ValueError, match="unknown environment"):
        SingleAgentEnv("nope_v0")
    with pytest.raises(ValueError, match="exactly one learning agent"):
        SingleAgentEnv("coexistence_v0", fixed={})
    env = make_single_agent_env("coexistence_v0")
    with pytest.raises(RuntimeError, match="reset"):
        env.step(STAY)
    env.reset(seed=0)
    for bad in (5, -1, 1.5):
        with pytest.raises(ValueError):
            env.step(bad)


def test_pickles_and_plays_the_same():
    env = make_single_agent_env("sharing_v0", max_cycles=30)
    copy = pickle.loads(pickle.dumps(env))
    moves = actions(2, 40)
    for a, b in zip(play(env, 1, moves), play(copy, 1, moves), strict=True):
        np.testing.assert_array_equal(a[0], b[0])
        assert a[1:] == b[1:]
