"""Sharing's fidelity options (SPEC §3, last bullet): ``start``, ``inventory_encoding`` and the
human's policy, on every face (ParallelEnv, AEC, vector env, Gymnasium adapter, sweep files)."""

from __future__ import annotations

import pickle
import textwrap

import numpy as np
import pytest
from gymnasium.utils import seeding
from pettingzoo.test import api_test, parallel_api_test

from empathy_zoo import EmpathyWrapper, FixedAgents, coexistence_v0, sharing_v0
from empathy_zoo.actions import NUM_ACTIONS, Action
from empathy_zoo.engine.sharing import BATTERY, FLOOR, INVENTORY_ENCODINGS, STARTS
from empathy_zoo.experiment.model import RunSpec
from empathy_zoo.experiment.sweep_file import load_sweep
from empathy_zoo.experiment.values import SweepConfigError
from empathy_zoo.gym_adapter import make_single_agent_env
from empathy_zoo.training import RunnerOptions, train_ensemble
from empathy_zoo.vector import VectorEnv

ROBOT, HUMAN = "robot_0", "human_0"
OPTIONS = {"start": "centre", "inventory_encoding": "authors"}
TINY = {
    "learning_starts": 64,
    "replay_capacity": 2_000,
    "epsilon_decay_steps": 500,
    "target_update_interval": 50,
    "hidden_size": 16,
}


def authors(n: int) -> np.float32:
    """SPEC §3: an agent holding ``n`` batteries is drawn as ``5·(n+1)/100``, as float32."""
    return np.float32((n + 1) / 20)


def positions(env) -> dict[str, tuple[int, int]]:
    pos = env.unwrapped.engine.pos[0]
    return {agent: tuple(pos[i].tolist()) for i, agent in enumerate(env.possible_agents)}


# ---------------------------------------------------------------------------- start = "centre"
@pytest.mark.parametrize(
    ("size", "robot", "human"),
    [
        (7, (2, 3), (3, 2)),  # the middle cell (3, 3) holds a battery: its nearest free cells, row-major
        (9, (4, 4), (3, 4)),  # the middle cell is free: the robot on it, the human on the first neighbour
        (8, (4, 4), (3, 4)),
        (5, (2, 2), (1, 2)),
    ],
)
def test_centre_start_cells(size, robot, human):
    env = sharing_v0.parallel_env(size=size, view=3, start="centre")
    for seed in (0, 1, 12345):
        env.reset(seed=seed)
        assert positions(env) == {ROBOT: robot, HUMAN: human}
        for _ in range(3):
            env.step({ROBOT: int(Action.STAY), HUMAN: int(Action.STAY)})
        env.reset()  # also without a seed
        assert positions(env) == {ROBOT: robot, HUMAN: human}


def test_centre_start_draws_no_random_number():
    """The env's generator is left untouched by a centre start: its first number goes to the first
    battery tie-break (a random start uses two numbers first)."""
    numbers = seeding.np_random(42)[0].random(3)
    for start, first_unused in (("centre", 0), ("random", 2)):
        env = sharing_v0.parallel_env(start=start)
        env.reset(seed=42)
        assert env.unwrapped.engine.streams.uniform(np.array([0]))[0] == numbers[first_unused], start


def test_centre_start_with_reset_options_places_the_others_in_centre_order():
    env = sharing_v0.parallel_env(start="centre")
    env.reset(seed=0, options={"positions": {ROBOT: (2, 3)}})
    assert positions(env) == {ROBOT: (2, 3), HUMAN: (3, 2)}
    env.reset(seed=0, options={"positions": {HUMAN: (2, 3)}})
    assert positions(env) == {ROBOT: (3, 2), HUMAN: (2, 3)}  # the robot takes the next free cell
    env.reset(seed=0, options={"batteries": [(0, 0)]})  # the middle cell is free of batteries now
    assert positions(env) == {ROBOT: (3, 3), HUMAN: (2, 3)}
    env.reset(seed=0, options={"positions": {ROBOT: (0, 0), HUMAN: (6, 6)}})  # placed agents stay where placed
    assert positions(env) == {ROBOT: (0, 0), HUMAN: (6, 6)}


def test_centre_start_in_the_vector_env_and_after_autoreset():
    vector = VectorEnv("sharing_v0", 4, fixed={HUMAN: "patrol"}, start="centre")
    vector.reset(seed=7)
    expected = np.array([[2, 3], [3, 2]])
    assert all(np.array_equal(vector.engine.pos[i], expected) for i in range(4))
    rng = np.random.default_rng(0)
    resets = 0
    for _ in range(600):
        out = vector.step(rng.integers(NUM_ACTIONS, size=(4, 1)))
        for i in np.flatnonzero(out.episode_over):
            resets += 1
            assert np.array_equal(vector.engine.pos[i], expected)
    assert resets >= 4


# ---------------------------------------------------------------------------- inventory_encoding = "authors"
def test_authors_values_in_observations_and_swapped_observations():
    env = EmpathyWrapper(sharing_v0.parallel_env(inventory_encoding="authors"))
    # robot at (1, 0) walks right over the batteries at (1, 1) and (1, 2); the human waits at (3, 1)
    obs, infos = env.reset(seed=0, options={"positions": {ROBOT: (1, 0), HUMAN: (3, 1)}, "batteries": [(1, 1), (1, 2), (5, 5)]})
    space = env.observation_space(ROBOT)
    assert space.high.max() == authors(9) and space.low.min() == BATTERY  # bounds: up to the 9 batteries of 7×7
    for n in range(3):
        if n:
            obs, _, _, _, infos = env.step({ROBOT: int(Action.RIGHT), HUMAN: int(Action.STAY)})
        assert infos[ROBOT]["batteries"] == n and infos[HUMAN]["batteries"] == 0
        robot_view, human_view = obs[ROBOT], obs[HUMAN]
        assert robot_view[12] == authors(n) and human_view[12] == authors(0)
        # robot at (1, n) sees the human at (3, 1): two rows down, 1 - n columns across
        assert robot_view[(2 + 2) * 5 + (2 + 1 - n)] == authors(0)
        # the human at (3, 1) sees the robot two rows up, n - 1 columns across
        assert human_view[(2 - 2) * 5 + (2 + n - 1)] == authors(n)
        assert set(np.unique(robot_view)) <= {np.float32(BATTERY), np.float32(FLOOR), authors(0), authors(n)}
        swapped = infos[ROBOT]["swapped_obs"][HUMAN]
        np.testing.assert_array_equal(swapped, human_view)  # SPEC §4: here, the other's own observation
        assert swapped[12] == authors(0) and swapped[(2 - 2) * 5 + (2 + n - 1)] == authors(n)
        np.testing.assert_array_equal(infos[HUMAN]["swapped_obs"][ROBOT], robot_view)
        for agent in (ROBOT, HUMAN):
            assert obs[agent].dtype == np.float32 and space.contains(obs[agent])
            assert space.contains(infos[agent]["swapped_obs"][ROBOT if agent == HUMAN else HUMAN])


def test_authors_observation_space_bounds_follow_the_largest_count():
    for size, batteries in ((7, 9), (9, 16), (5, 4)):
        env = sharing_v0.parallel_env(size=size, view=3, inventory_encoding="authors")
        space = env.observation_space(ROBOT)
        assert space.high.max() == authors(batteries) and space.low.min() == np.float32(-1.0)
        assert sharing_v0.parallel_env(size=size, view=3).observation_space(ROBOT).high.max() == 1 + batteries
    env = sharing_v0.parallel_env(inventory_encoding="authors")
    assert env.observation_space(ROBOT) is env.observation_space(HUMAN)


def test_authors_observations_stay_inside_the_space_through_whole_episodes():
    env = FixedAgents(sharing_v0.parallel_env(**OPTIONS), {HUMAN: "random_walk"})
    space = env.observation_space(ROBOT)
    rng = np.random.default_rng(3)
    obs, _ = env.reset(seed=5)
    seen = set()
    for _ in range(3000):
        if not env.agents:
            obs, _ = env.reset()
        assert space.contains(obs[ROBOT])
        seen |= set(obs[ROBOT].tolist())
        obs, *_ = env.step({ROBOT: int(rng.integers(NUM_ACTIONS))})
    assert {authors(0), authors(1), authors(2)} <= {np.float32(v) for v in seen}


# ---------------------------------------------------------------------------- every face, same trajectories
def test_vector_env_equals_parallel_envs_with_the_options_on():
    fixed = {HUMAN: "random_walk"}
    seeds = [0, 1, 17]
    envs = [FixedAgents(sharing_v0.parallel_env(**OPTIONS), fixed) for _ in seeds]
    vector = VectorEnv("sharing_v0", len(seeds), fixed=fixed, **OPTIONS)
    observations = vector.reset(seed=seeds)
    for i, (env, seed) in enumerate(zip(envs, seeds, strict=True)):
        np.testing.assert_array_equal(observations[i, 0], env.reset(seed=seed)[0][ROBOT])
    rng = np.random.default_rng(9)
    finished = 0
    for t in range(400):
        actions = rng.integers(NUM_ACTIONS, size=(len(seeds), 1))
        out = vector.step(actions)
        for i, env in enumerate(envs):
            obs, rew, term, trunc, _ = env.step({ROBOT: int(actions[i, 0])})
            where = f"env {i} step {t}"
            np.testing.assert_array_equal(out.final_observations[i, 0], obs[ROBOT], err_msg=where)
            swapped = env.unwrapped.swapped_observation(ROBOT, HUMAN)
            np.testing.assert_array_equal(out.other_swapped[i, 0], swapped, err_msg=where)
            assert out.rewards[i, 0] == np.float32(rew[ROBOT]), where
            assert (bool(out.terminated[i, 0]), bool(out.truncated[i, 0])) == (term[ROBOT], trunc[ROBOT]), where
            assert bool(out.episode_over[i]) == (not env.agents), where
            if not env.agents:
                finished += 1
                np.testing.assert_array_equal(out.observations[i, 0], env.reset()[0][ROBOT], err_msg=where)
    assert finished >= 3, "the comparison should span whole episodes"


def test_gym_adapter_forwards_the_options():
    single = make_single_agent_env("sharing_v0", fixed={HUMAN: "random_walk"}, **OPTIONS)
    obs, _ = single.reset(seed=4)
    env = FixedAgents(sharing_v0.parallel_env(**OPTIONS), {HUMAN: "random_walk"})
    np.testing.assert_array_equal(obs, env.reset(seed=4)[0][ROBOT])
    assert single.observation_space == env.observation_space(ROBOT)
    assert obs[12] == authors(0)


@pytest.mark.filterwarnings("ignore:ignoring unknown reset option")  # PettingZoo's test passes foreign options
def test_pettingzoo_api_tests_pass_with_the_options():
    parallel_api_test(sharing_v0.parallel_env(**OPTIONS), num_cycles=200)
    api_test(sharing_v0.env(**OPTIONS), num_cycles=50)


def test_the_options_survive_pickling():
    env = pickle.loads(pickle.dumps(sharing_v0.parallel_env(size=9, **OPTIONS)))
    engine = env.unwrapped.engine
    assert (engine.size, engine.start, engine.inventory_encoding) == (9, "centre", "authors")


# ---------------------------------------------------------------------------- defaults unchanged
def _trajectory(env, seed: int, steps: int) -> list:
    rng = np.random.default_rng(seed)
    record = [env.reset(seed=seed)]
    for _ in range(steps):
        if not env.agents:
            record.append(env.reset())
        record.append(env.step({agent: int(rng.integers(NUM_ACTIONS)) for agent in env.agents}))
    return record


def _equal(a, b) -> bool:
    if isinstance(a, dict):
        return isinstance(b, dict) and list(a) == list(b) and all(_equal(a[k], b[k]) for k in a)
    if isinstance(a, (list, tuple)):
        return isinstance(b, (list, tuple)) and len(a) == len(b) and all(_equal(x, y) for x, y in zip(a, b, strict=True))
    if isinstance(a, np.ndarray):
        return isinstance(b, np.ndarray) and a.dtype == b.dtype and np.array_equal(a, b)
    return type(a) is type(b) and a == b


def test_explicit_defaults_give_the_default_env_bit_for_bit():
    default = _trajectory(sharing_v0.parallel_env(), seed=11, steps=1500)
    explicit = _trajectory(sharing_v0.parallel_env(start="random", inventory_encoding="count_plus_one"), 11, 1500)
    assert _equal(default, explicit)
    assert STARTS[0] == "random" and INVENTORY_ENCODINGS[0] == "count_plus_one"
    engine = sharing_v0.parallel_env().unwrapped.engine
    assert engine.start_order is None and engine.obs_high == 10.0
    # the integer encoding: an agent is 1 + its count
    assert all(value == int(value) for step in default[1:] if len(step) == 5 for o in step[0].values() for value in o)


def test_each_option_changes_the_trajectory():
    default = _trajectory(sharing_v0.parallel_env(), seed=11, steps=300)
    for option in ({"start": "centre"}, {"inventory_encoding": "authors"}):
        assert not _equal(default, _trajectory(sharing_v0.parallel_env(**option), seed=11, steps=300)), option


# ---------------------------------------------------------------------------- bad values
@pytest.mark.parametrize(
    ("kwargs", "named"),
    [
        ({"start": "middle"}, "start must be one of 'random', 'centre'; got 'middle'"),
        ({"start": None}, "start must be one of"),
        ({"inventory_encoding": "count"}, "inventory_encoding must be one of 'count_plus_one', 'authors'; got 'count'"),
        ({"inventory_encoding": 1}, "inventory_encoding must be one of"),
    ],
)
def test_bad_values_raise_naming_the_argument_and_the_choices(kwargs, named):
    for make in (
        lambda: sharing_v0.parallel_env(**kwargs),
        lambda: sharing_v0.env(**kwargs),
        lambda: VectorEnv("sharing_v0", 2, **kwargs),
        lambda: make_single_agent_env("sharing_v0", **kwargs),
    ):
        with pytest.raises(ValueError) as caught:
            make()
        assert named in str(caught.value)
    with pytest.raises(ValueError, match=named.split(" must")[0]):
        RunSpec.of(env="sharing_v0", env_kwargs=kwargs, steps=10, eval_interval=10, eval_episodes=1)


def test_coexistence_takes_no_sharing_start():
    for make in (
        lambda: coexistence_v0.parallel_env(start="centre"),
        lambda: VectorEnv("coexistence_v0", 2, start="centre"),
        lambda: make_single_agent_env("coexistence_v0", start="centre"),
    ):
        with pytest.raises(ValueError, match="start must be one of 'rules', 'random', 'centre_corner'"):
            make()


@pytest.mark.parametrize("name", ["inventory_encoding"])
def test_coexistence_takes_no_fidelity_argument(name):
    value = {"inventory_encoding": "authors"}[name]
    for make in (
        lambda: coexistence_v0.parallel_env(**{name: value}),
        lambda: coexistence_v0.env(**{name: value}),
        lambda: VectorEnv("coexistence_v0", 2, **{name: value}),
        lambda: make_single_agent_env("coexistence_v0", **{name: value}),
    ):
        with pytest.raises(TypeError, match=f"coexistence_v0 takes no argument.*'{name}'"):
            make()
    with pytest.raises(ValueError, match=f"coexistence_v0 takes no argument.*'{name}'"):
        RunSpec.of(env="coexistence_v0", env_kwargs={name: value}, steps=10, eval_interval=10, eval_episodes=1)


def test_unknown_keywords_still_raise():
    with pytest.raises(TypeError, match="grid_size"):
        sharing_v0.parallel_env(grid_size=9)
    with pytest.raises(TypeError, match="grid_size"):
        VectorEnv("sharing_v0", 2, grid_size=9)


# ---------------------------------------------------------------------------- sweep files and training
SWEEP = """
[sweep]
seeds = 2
steps = 1000
eval_interval = 500
eval_episodes = 2

[envs.sharing_v0]

[envs.sharing_centre]
env = "sharing_v0"
start = "centre"
inventory_encoding = "authors"
fixed = { human_0 = "random_walk" }

[[methods]]
method = "empathic_dqn"
selfishness = [1.0, 0.5]
"""


def _sweep(tmp_path, text: str):
    path = tmp_path / "sweep.toml"
    path.write_text(textwrap.dedent(text), encoding="utf-8")
    return path


def test_sweep_file_carries_the_options_into_the_run_specs(tmp_path):
    specs = load_sweep(_sweep(tmp_path, SWEEP))
    centre = [s for s in specs if s.variant.label == "sharing_centre"]
    assert len(centre) == 4 and len(specs) == 8
    for spec in centre:
        assert dict(spec.env_kwargs) == {"start": "centre", "inventory_encoding": "authors"}
        assert spec.fixed_policies() == {HUMAN: "random_walk"}
        assert spec.config()["env_kwargs"] == {"start": "centre", "inventory_encoding": "authors"}
        assert spec.run_id.startswith("sharing_centre__empathic_dqn-")
    plain = [s for s in specs if s.variant.label == "sharing_v0"]
    assert all(dict(s.env_kwargs) == {} and s.fixed_policies() == {HUMAN: "patrol"} for s in plain)
    assert {s.experiment_hash() for s in centre}.isdisjoint({s.experiment_hash() for s in plain})
    assert centre[0].ensemble_key() != plain[0].ensemble_key()  # never trained in one ensemble


@pytest.mark.parametrize(
    ("table", "message"),
    [
        ('[envs.c]\nenv = "coexistence_v0"\nstart = "centre"', "start must be one of 'rules', 'random', 'centre_corner'"),
        (
            '[envs.c]\nenv = "coexistence_v0"\ninventory_encoding = "authors"',
            "coexistence_v0 takes no argument 'inventory_encoding'",
        ),
        ('[envs.s]\nenv = "sharing_v0"\nstart = "middle"', "start must be one of 'random', 'centre'; got 'middle'"),
        ('[envs.s]\nenv = "sharing_v0"\ninventory_encoding = "x"', "inventory_encoding must be one of"),
        ('[envs.s]\nenv = "sharing_v0"\nstart = 1', "[envs.s] start: expected str"),
    ],
)
def test_sweep_file_rejects_bad_options(tmp_path, table, message):
    path = _sweep(tmp_path, SWEEP.replace("[envs.sharing_v0]", table))
    with pytest.raises(SweepConfigError) as caught:
        load_sweep(path)
    assert message in str(caught.value) and str(path) in str(caught.value)


def test_training_with_the_authors_encoding(tmp_path):
    specs = [
        RunSpec.of(
            env="sharing_v0",
            method="empathic_dqn",
            settings={**TINY, "selfishness": b},
            seed=s,
            steps=400,
            eval_interval=200,
            eval_episodes=2,
            fixed={HUMAN: "random_walk"},
            env_kwargs={**OPTIONS, "max_cycles": 100},
        )
        for s, b in ((0, 0.5), (1, 0.25))
    ]
    results = train_ensemble(specs, tmp_path, RunnerOptions(progress=False, checkpoint_interval=0), write_results=False)
    assert [r["run_id"] for r in results] == [s.run_id for s in specs]
    for result in results:
        assert result["config"]["env_kwargs"] == {**OPTIONS, "max_cycles": 100}
        assert [e["step"] for e in result["eval"]] == [200, 400]
        assert result["train"]["survival"], "no training episode finished"
