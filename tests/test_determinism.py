"""Same seed and actions -> same trajectory, on every face of the engine (DESIGN: one source of truth).

The vector env must equal N independent ParallelEnvs step for step, across autoresets.
"""

from __future__ import annotations

import numpy as np
import pytest

from empathy_zoo import FixedAgents, coexistence_v0, sharing_v0
from empathy_zoo.actions import NUM_ACTIONS
from empathy_zoo.environments import DEFAULT_POLICIES
from empathy_zoo.metrics import METRIC_NAMES
from empathy_zoo.vector import VectorEnv

MODULES = [coexistence_v0, sharing_v0]
IDS = [module.__name__.rsplit(".", 1)[-1] for module in MODULES]


def env_name(module) -> str:
    return module.__name__.rsplit(".", 1)[-1]


def rollout(env, seed: int, steps: int, action_seed: int) -> list:
    """Whole episodes (resetting without a seed in between): every value the env returned."""
    rng = np.random.default_rng(action_seed)
    record = [("reset", *env.reset(seed=seed))]
    for _ in range(steps):
        if not env.agents:
            record.append(("reset", *env.reset()))
        actions = {agent: int(rng.integers(NUM_ACTIONS)) for agent in env.agents}
        record.append(("step", *env.step(actions)))
    return record


def flatten(record: list) -> list:
    """The record as a flat list of comparable scalars and arrays (dict keys kept in order)."""
    out = []

    def walk(value):
        if isinstance(value, dict):
            for key, item in value.items():
                out.append(key)
                walk(item)
        elif isinstance(value, (list, tuple)):
            out.append(len(value))
            for item in value:
                walk(item)
        else:
            out.append(value)

    walk(record)
    return out


def same(a: list, b: list) -> bool:
    flat_a, flat_b = flatten(a), flatten(b)
    if len(flat_a) != len(flat_b):
        return False
    for x, y in zip(flat_a, flat_b, strict=True):
        if isinstance(x, np.ndarray) or isinstance(y, np.ndarray):
            if not (isinstance(x, np.ndarray) and isinstance(y, np.ndarray) and x.dtype == y.dtype and np.array_equal(x, y)):
                return False
        elif x != y or type(x) is not type(y):
            return False
    return True


def count_episodes(record: list) -> int:
    return sum(entry[0] == "reset" for entry in record)


@pytest.mark.parametrize("module", MODULES, ids=IDS)
def test_same_seed_same_actions_same_episodes(module):
    a = rollout(module.parallel_env(), seed=11, steps=1500, action_seed=5)
    b = rollout(module.parallel_env(), seed=11, steps=1500, action_seed=5)
    assert count_episodes(a) >= 3, "the test should cover several whole episodes"
    assert same(a, b)


@pytest.mark.parametrize("module", MODULES, ids=IDS)
def test_different_seeds_differ(module):
    a = rollout(module.parallel_env(), seed=11, steps=300, action_seed=5)
    b = rollout(module.parallel_env(), seed=12, steps=300, action_seed=5)
    assert not same(a, b)


@pytest.mark.parametrize("module", MODULES, ids=IDS)
def test_reset_with_the_same_seed_repeats_the_episode(module):
    env = module.parallel_env()
    first = rollout(env, seed=3, steps=200, action_seed=1)
    second = rollout(env, seed=3, steps=200, action_seed=1)
    assert same(first, second)


@pytest.mark.parametrize("module", MODULES, ids=IDS)
def test_fixed_agents_same_seed_same_trajectory(module):
    fixed = DEFAULT_POLICIES[env_name(module)]
    a = rollout(FixedAgents(module.parallel_env(), fixed), seed=21, steps=1500, action_seed=2)
    b = rollout(FixedAgents(module.parallel_env(), fixed), seed=21, steps=1500, action_seed=2)
    assert count_episodes(a) >= 3
    assert same(a, b)
    c = rollout(FixedAgents(module.parallel_env(), fixed), seed=22, steps=1500, action_seed=2)
    assert not same(a, c)


def test_fixed_random_walk_depends_on_the_seed_not_on_a_global_rng():
    fixed = DEFAULT_POLICIES["coexistence_v0"]
    a = rollout(FixedAgents(coexistence_v0.parallel_env(), fixed), seed=4, steps=200, action_seed=0)
    np.random.seed(123)  # a global RNG must not matter
    b = rollout(FixedAgents(coexistence_v0.parallel_env(), fixed), seed=4, steps=200, action_seed=0)
    assert same(a, b)


def lockstep(module, fixed: dict | None, seeds: list[int], steps: int, action_seed: int, **env_kwargs) -> int:
    """Step ``len(seeds)`` ParallelEnvs (in FixedAgents when ``fixed``) and one VectorEnv with the same
    actions and compare everything; returns the number of finished episodes."""
    name = env_name(module)
    n = len(seeds)
    envs = [module.parallel_env(**env_kwargs) for _ in seeds]
    if fixed:
        envs = [FixedAgents(env, fixed) for env in envs]
    vector = VectorEnv(name, n, fixed=fixed, **env_kwargs)
    learners = vector.learners
    all_agents = vector.agents
    assert learners == list(envs[0].possible_agents)
    columns = [all_agents.index(agent) for agent in learners]

    observations = vector.reset(seed=seeds)
    assert observations.shape == (n, len(learners), 25) and observations.dtype == np.float32
    for i, (env, seed) in enumerate(zip(envs, seeds, strict=True)):
        obs, _ = env.reset(seed=seed)
        for k, agent in enumerate(learners):
            np.testing.assert_array_equal(observations[i, k], obs[agent])

    rng = np.random.default_rng(action_seed)
    finished = 0
    for t in range(steps):
        actions = rng.integers(NUM_ACTIONS, size=(n, len(learners)))
        out = vector.step(actions)
        for i, env in enumerate(envs):
            live = list(env.agents)
            obs, rew, term, trunc, _ = env.step({agent: int(actions[i, k]) for k, agent in enumerate(learners) if agent in live})
            for k, agent in enumerate(learners):
                column = columns[k]
                if agent in live:
                    where = f"env {i} step {t} agent {agent}"
                    np.testing.assert_array_equal(out.final_observations[i, k], obs[agent], err_msg=where)
                    assert out.rewards[i, column] == np.float32(rew[agent]), where
                    assert bool(out.terminated[i, column]) == term[agent], where
                    assert bool(out.truncated[i, column]) == trunc[agent], where
                else:  # the agent had left before this step: nothing happens to it
                    assert out.rewards[i, column] == 0 and not out.terminated[i, column]
            over = not env.agents
            assert bool(out.episode_over[i]) == over, f"env {i} step {t}"
            if over:
                finished += 1
                metrics = env.unwrapped.engine.episode_metrics(np.array([0]))
                row = list(out.finished["env"]).index(i)
                for metric in (*METRIC_NAMES, "length"):
                    assert out.finished[metric][row] == metrics[metric][0], (metric, i, t)
                obs, _ = env.reset()
                for k, agent in enumerate(learners):
                    np.testing.assert_array_equal(out.observations[i, k], obs[agent])
            else:
                np.testing.assert_array_equal(out.observations[i], out.final_observations[i])
        assert sorted(out.finished["env"].tolist()) == np.flatnonzero(out.episode_over).tolist()
    return finished


@pytest.mark.parametrize("module", MODULES, ids=IDS)
def test_vector_env_equals_parallel_envs_with_fixed_agents(module):
    finished = lockstep(module, DEFAULT_POLICIES[env_name(module)], seeds=[0, 1, 17], steps=2000, action_seed=9)
    assert finished >= 6, "the comparison should span several whole episodes in every env"


@pytest.mark.parametrize("module", MODULES, ids=IDS)
def test_vector_env_without_fixed_agents_equals_bare_parallel_env(module):
    finished = lockstep(module, None, seeds=[5, 6], steps=2000, action_seed=4)
    assert finished >= 4


SEVERAL = [(coexistence_v0, {"num_cats": 3}), (sharing_v0, {"num_humans": 2})]
"""Each environment with several other agents (SPEC §3b)."""


@pytest.mark.parametrize("module, env_kwargs", SEVERAL, ids=IDS)
def test_vector_env_equals_parallel_envs_with_several_others(module, env_kwargs):
    (policy,) = DEFAULT_POLICIES[env_name(module)].values()
    others = module.parallel_env(**env_kwargs).possible_agents[1:]
    finished = lockstep(module, dict.fromkeys(others, policy), seeds=[0, 1, 17], steps=1000, action_seed=9, **env_kwargs)
    assert finished >= 3


@pytest.mark.parametrize("module, env_kwargs", SEVERAL, ids=IDS)
def test_vector_env_with_several_learners_equals_bare_parallel_env(module, env_kwargs):
    finished = lockstep(module, None, seeds=[5, 6], steps=1000, action_seed=4, **env_kwargs)
    assert finished >= 2


@pytest.mark.parametrize("module", MODULES, ids=IDS)
def test_vector_env_seed_int_means_consecutive_seeds(module):
    name = env_name(module)
    a = VectorEnv(name, 3, fixed=DEFAULT_POLICIES[name])
    b = VectorEnv(name, 3, fixed=DEFAULT_POLICIES[name])
    np.testing.assert_array_equal(a.reset(seed=40), b.reset(seed=[40, 41, 42]))
    actions = np.random.default_rng(0).integers(NUM_ACTIONS, size=(100, 3, 1))
    for step_actions in actions:
        out_a, out_b = a.step(step_actions), b.step(step_actions)
        np.testing.assert_array_equal(out_a.observations, out_b.observations)
        np.testing.assert_array_equal(out_a.rewards, out_b.rewards)
