"""PettingZoo API conformance, seeding, spaces, pickling and rendering of both environments."""

from __future__ import annotations

import pickle

import cloudpickle
import numpy as np
import pytest
from pettingzoo.test import api_test, parallel_api_test, parallel_seed_test

from empathy_zoo import ENVIRONMENTS, EmpathyWrapper, FixedAgents, coexistence_v0, sharing_v0
from empathy_zoo.actions import NUM_ACTIONS
from empathy_zoo.environments import DEFAULT_POLICIES

MODULES = [coexistence_v0, sharing_v0]
IDS = [module.__name__.rsplit(".", 1)[-1] for module in MODULES]

# PettingZoo's API tests pass a foreign reset option on purpose; the envs ignore it with a warning.
pytestmark = pytest.mark.filterwarnings("ignore:ignoring unknown reset option")


def env_name(module) -> str:
    return module.__name__.rsplit(".", 1)[-1]


def play(env, seed: int, steps: int, action_seed: int = 0) -> list:
    """Reset with ``seed`` and step with seeded random actions; the full record of what happened."""
    rng = np.random.default_rng(action_seed)
    record = [env.reset(seed=seed)]
    for _ in range(steps):
        if not env.agents:
            record.append(env.reset())
            continue
        record.append(env.step({agent: int(rng.integers(NUM_ACTIONS)) for agent in env.agents}))
    return record


def assert_same(a, b) -> None:
    """Nested equality of dicts, tuples, lists and arrays (arrays compared exactly, dtype too)."""
    if isinstance(a, np.ndarray):
        assert isinstance(b, np.ndarray) and a.dtype == b.dtype
        np.testing.assert_array_equal(a, b)
    elif isinstance(a, dict):
        assert isinstance(b, dict) and list(a) == list(b)
        for key in a:
            assert_same(a[key], b[key])
    elif isinstance(a, (list, tuple)):
        assert type(a) is type(b) and len(a) == len(b)
        for x, y in zip(a, b, strict=True):
            assert_same(x, y)
    else:
        assert a == b and type(a) is type(b)


@pytest.mark.parametrize("module", MODULES, ids=IDS)
def test_parallel_api(module):
    parallel_api_test(module.parallel_env(), num_cycles=600)


@pytest.mark.parametrize("module", MODULES, ids=IDS)
def test_aec_api(module):
    api_test(module.env(), num_cycles=200)


@pytest.mark.parametrize("module", MODULES, ids=IDS)
def test_parallel_seed(module):
    parallel_seed_test(module.parallel_env, num_cycles=300)


@pytest.mark.parametrize("module", MODULES, ids=IDS)
def test_wrapped_envs_pass_parallel_api(module):
    fixed = DEFAULT_POLICIES[env_name(module)]
    parallel_api_test(FixedAgents(module.parallel_env(), fixed), num_cycles=600)
    parallel_api_test(EmpathyWrapper(module.parallel_env()), num_cycles=600)
    parallel_api_test(EmpathyWrapper(FixedAgents(module.parallel_env(), fixed)), num_cycles=600)


@pytest.mark.parametrize("module", MODULES, ids=IDS)
def test_metadata_name_matches_module(module):
    assert module.parallel_env().metadata["name"] == env_name(module)
    assert module.env().metadata["name"] == env_name(module)
    assert ENVIRONMENTS[env_name(module)] is module


@pytest.mark.parametrize("module", MODULES, ids=IDS)
def test_spaces_are_the_same_object_across_calls(module):
    env = module.parallel_env()
    for agent in env.possible_agents:
        assert env.observation_space(agent) is env.observation_space(agent)
        assert env.action_space(agent) is env.action_space(agent)
        env.reset(seed=1)
        assert env.observation_space(agent) is env.observation_space(agent)
        assert env.action_space(agent).n == NUM_ACTIONS
        assert env.observation_space(agent).shape == (25,)
        assert env.observation_space(agent).dtype == np.float32


@pytest.mark.parametrize("module", MODULES, ids=IDS)
def test_observations_lie_in_their_space(module):
    env = module.parallel_env()
    for seed in range(5):
        record = play(env, seed=seed, steps=300, action_seed=seed)
        for entry in record:
            for agent, observation in entry[0].items():
                assert env.observation_space(agent).contains(observation), (agent, observation)


@pytest.mark.parametrize("dumps", [pickle.dumps, cloudpickle.dumps], ids=["pickle", "cloudpickle"])
@pytest.mark.parametrize("module", MODULES, ids=IDS)
@pytest.mark.parametrize("wrapped", [False, True], ids=["raw", "wrapped"])
def test_pickle_round_trip_continues_identically(module, dumps, wrapped):
    def make():
        env = module.parallel_env()
        return EmpathyWrapper(FixedAgents(env, DEFAULT_POLICIES[env_name(module)])) if wrapped else env

    original = make()
    clone = pickle.loads(dumps(original))
    assert_same(play(original, seed=7, steps=120), play(clone, seed=7, steps=120))


@pytest.mark.parametrize("max_cycles", [1, 3, 8])
@pytest.mark.parametrize("module, reward", [(coexistence_v0, 1.0), (sharing_v0, 0.0)], ids=IDS)
def test_truncation_at_max_cycles(module, reward, max_cycles):
    """Agents standing still, apart and off the batteries: everyone is truncated at max_cycles."""
    env = module.parallel_env(max_cycles=max_cycles)
    a, b = env.possible_agents
    env.reset(seed=0, options={"positions": {a: (0, 0), b: (3, 2)}})
    for t in range(1, max_cycles + 1):
        _, rewards, terminations, truncations, _ = env.step({a: 4, b: 4})
        assert rewards == {a: reward, b: reward}
        assert terminations == {a: False, b: False}
        assert truncations == {a: t == max_cycles, b: t == max_cycles}
    assert env.agents == []


@pytest.mark.parametrize("module", MODULES, ids=IDS)
def test_render_ansi_is_a_text_grid(module):
    env = module.parallel_env(render_mode="ansi")
    env.reset(seed=3)
    text = env.render()
    assert isinstance(text, str)
    rows = text.strip("\n").split("\n")
    assert len(rows) == env.unwrapped.engine.size
    assert all(len(row.split(" ")) == env.unwrapped.engine.size for row in rows)
    for symbol in env.unwrapped.engine.symbols:
        assert symbol in text


@pytest.mark.parametrize("module", MODULES, ids=IDS)
def test_render_rgb_array_is_an_image(module):
    env = module.parallel_env(render_mode="rgb_array")
    env.reset(seed=3)
    image = env.render()
    assert isinstance(image, np.ndarray)
    assert image.ndim == 3 and image.shape[2] == 3 and image.dtype == np.uint8
    assert image.shape[0] > 0 and image.shape[1] > 0


@pytest.mark.parametrize("module", MODULES, ids=IDS)
def test_no_render_mode_renders_nothing(module):
    env = module.parallel_env()
    env.reset(seed=0)
    assert env.render() is None


@pytest.mark.parametrize("module", MODULES, ids=IDS)
@pytest.mark.parametrize("mode", ["human", "rgb", "", 3])
def test_bad_render_mode_raises(module, mode):
    with pytest.raises(ValueError, match="render_mode"):
        module.parallel_env(render_mode=mode)
