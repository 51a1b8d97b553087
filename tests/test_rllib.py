"""RLlib on the suite's envs: its ``ParallelPettingZooEnv`` wrapper, and PPO on the new API stack
training the Coexistence robot while the cat stays a fixed agent (``FixedAgents``).

RLlib pins its own Gymnasium release, so it lives in an environment of its own (``.ci/run``'s
second stage): ``pip install torch==2.13.0 && pip install -e ".[test-rllib]"``, then
``python -m pytest -m rllib tests/test_rllib.py``. Without RLlib this module is skipped.

RLlib's ``ParallelPettingZooEnv`` sets ``__all__`` only when *every* agent is terminated (or
every one truncated). When Coexistence's robot is harmed, the robot is terminated and the cat
truncated, so the wrapper does not flag the end: drive it by ``par_env.agents``, or make the cat
a fixed agent, which is how the suite trains anyway (see docs/ecosystem.md).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from empathy_zoo import FixedAgents, RandomWalk, coexistence_v0, sharing_v0
from empathy_zoo.fixed_agents import policy_seed
from empathy_zoo.grid import MOVES

pettingzoo_env = pytest.importorskip(
    "ray.rllib.env.wrappers.pettingzoo_env",
    exc_type=ImportError,
    reason='RLlib is not installed (pip install -e ".[test-rllib]")',
)
pytestmark = pytest.mark.rllib
ParallelPettingZooEnv = pettingzoo_env.ParallelPettingZooEnv

ROBOT, CAT = "robot_0", "cat_0"
ENV_CONFIG = {"max_cycles": 50}
"""Short episodes, so every training iteration completes some and reports their returns."""
ITERATIONS = 2
BATCH = 200
"""Env steps per training iteration."""
GREEDY_SEEDS = (100, 101, 102)
STEPS = 1000
ENVS = {
    "coexistence_v0": lambda: coexistence_v0.parallel_env(),
    "sharing_v0": lambda: sharing_v0.parallel_env(),
    "coexistence_v0+FixedAgents": lambda: FixedAgents(coexistence_v0.parallel_env(), {CAT: "random_walk"}),
}


def robot_env(config: dict | None = None) -> ParallelPettingZooEnv:
    """The env RLlib trains on: Coexistence with the cat driven inside, so the robot is its only agent."""
    return ParallelPettingZooEnv(FixedAgents(coexistence_v0.parallel_env(**(config or {})), {CAT: "random_walk"}))


# ------------------------------------------------------------------------------ the env wrapper
@pytest.mark.parametrize("name", sorted(ENVS))
def test_rllib_parallel_pettingzoo_env_steps_through_episodes(name: str) -> None:
    env = ParallelPettingZooEnv(ENVS[name]())
    assert set(env.observation_space) == set(env.par_env.possible_agents)
    rng = np.random.default_rng(0)
    obs, _infos = env.reset(seed=0)
    live = set(obs)
    episodes = left = 0
    for _ in range(STEPS):
        actions = {agent: int(rng.integers(0, 5)) for agent in live}
        obs, rewards, terminated, truncated, _infos = env.step(actions)
        assert set(obs) == set(rewards) == live, "every agent that acted gets its last observation and reward"
        for agent in live:
            assert env.observation_space[agent].contains(obs[agent])
        gone = {agent for agent in live if terminated[agent] or truncated[agent]}
        if terminated["__all__"] or truncated["__all__"] or not env.par_env.agents:
            assert not env.par_env.agents
            episodes += 1
            obs, _infos = env.reset()
            live = set(obs)
        else:
            left += len(gone)  # an agent left mid-episode (a harmed cat): it gets no further action
            live -= gone
            assert live == set(env.par_env.agents)
    assert episodes >= 1
    if name == "coexistence_v0":
        assert left >= 1, "with this seed the robot harms the cat at least once"


# ------------------------------------------------------------------- PPO on the new API stack
@pytest.fixture(scope="module")
def trained():
    """PPO trained for ``ITERATIONS`` tiny iterations in this process (no remote env runners or
    learners); yields the algorithm and the result of every iteration."""
    import ray
    import torch
    from ray.rllib.algorithms.ppo import PPOConfig
    from ray.rllib.core.rl_module.default_model_config import DefaultModelConfig
    from ray.tune.registry import register_env

    torch.manual_seed(0)
    ray.init(num_cpus=1, include_dashboard=False, logging_level="ERROR", log_to_driver=False)
    register_env("coexistence_v0_robot", robot_env)
    config = (
        PPOConfig()
        .api_stack(enable_rl_module_and_learner=True, enable_env_runner_and_connector_v2=True)
        .environment("coexistence_v0_robot", env_config=ENV_CONFIG)
        .env_runners(num_env_runners=0, num_envs_per_env_runner=1)
        .learners(num_learners=0)
        .multi_agent(policies={ROBOT}, policy_mapping_fn=lambda agent_id, episode, **kwargs: ROBOT)
        .rl_module(model_config=DefaultModelConfig(fcnet_hiddens=[16], head_fcnet_hiddens=[]))
        .training(train_batch_size_per_learner=BATCH, minibatch_size=BATCH // 2, num_epochs=1)
        .debugging(seed=0)
    )
    algo = config.build_algo()
    try:
        yield algo, [algo.train() for _ in range(ITERATIONS)]
    finally:
        algo.stop()
        ray.shutdown()


def test_rllib_trains_the_robot_alone_on_the_new_api_stack(trained) -> None:
    algo, results = trained
    assert algo.config.enable_rl_module_and_learner and algo.config.enable_env_runner_and_connector_v2
    modules = set(algo.env_runner.module.keys())
    assert CAT not in modules and modules == {ROBOT}, "RLlib holds a module for the robot only"
    assert algo.env_runner.env.envs[0].unwrapped.par_env.possible_agents == [ROBOT]
    for result in results:
        trained_modules = set(result["learners"]) - {"__all_modules__"}
        assert CAT not in trained_modules and trained_modules == {ROBOT}, "the learner updated the robot only"
        runners = result["env_runners"]
        assert set(runners["module_episode_returns_mean"]) == {ROBOT}
        assert math.isfinite(runners["episode_return_mean"]) and math.isfinite(runners["episode_len_mean"])
        # +1 per step the robot is operative: a return is the robot's survival, at most max_cycles
        assert 0 <= runners["episode_return_mean"] <= runners["episode_len_mean"] <= ENV_CONFIG["max_cycles"]
    assert results[-1]["num_env_steps_sampled_lifetime"] >= ITERATIONS * BATCH


def greedy_action(module, observation: np.ndarray) -> int:
    """The RLlib module's greedy action (its inference distribution made deterministic)."""
    import torch

    with torch.no_grad():
        out = module.forward_inference({"obs": torch.as_tensor(observation[None])})
    dist = module.get_inference_action_dist_cls().from_logits(out["action_dist_inputs"]).to_deterministic()
    return int(dist.sample()[0])


def run_greedy_episode(module, env: ParallelPettingZooEnv, seed: int) -> dict:
    """One greedy episode through RLlib's wrapper: what RLlib saw, and every position on the grid."""
    engine = env.par_env.unwrapped.engine
    robot = env.par_env.unwrapped.possible_agents.index(ROBOT)
    obs, _ = env.reset(seed=seed)
    record = {"actions": [], "positions": [engine.pos[0].copy()], "cat_present": [True], "rewards": [], "harmed": 0}
    while True:
        action = greedy_action(module, obs[ROBOT])
        obs, rewards, terminated, truncated, infos = env.step({ROBOT: action})
        assert set(rewards) == {ROBOT}, "RLlib never sees the cat"
        record["actions"].append(action)
        record["positions"].append(engine.pos[0].copy())
        record["cat_present"].append(CAT in env.par_env.unwrapped.agents)
        record["rewards"].append(rewards[ROBOT])
        record["harmed"] += len(infos[ROBOT]["harmed"])
        if terminated["__all__"] or truncated["__all__"]:
            record["episode_info"] = infos[ROBOT].get("episode")  # the env's own report, as RLlib received it
            break
    record["metrics"] = engine.episode_metrics(np.array([0]), learner=robot)
    return record


def replay_in_the_suite(actions: list[int], seed: int) -> dict:
    """The suite's own FixedAgents run with the same seed and the same robot actions."""
    env = FixedAgents(coexistence_v0.parallel_env(**ENV_CONFIG), {CAT: "random_walk"})
    engine = env.unwrapped.engine
    robot = env.unwrapped.possible_agents.index(ROBOT)
    env.reset(seed=seed)
    positions = [engine.pos[0].copy()]
    for action in actions:
        env.step({ROBOT: action})
        positions.append(engine.pos[0].copy())
    assert not env.agents, "the replay ends where RLlib's episode ended"
    return {"positions": positions, "metrics": engine.episode_metrics(np.array([0]), learner=robot)}


@pytest.fixture(scope="module")
def greedy_episodes(trained) -> dict[int, dict]:
    algo, _ = trained
    module = algo.get_module(ROBOT)
    env = robot_env(ENV_CONFIG)
    return {seed: run_greedy_episode(module, env, seed) for seed in GREEDY_SEEDS}


def test_rllib_leaves_the_cat_to_its_random_walk(greedy_episodes) -> None:
    cat = coexistence_v0.parallel_env().possible_agents.index(CAT)
    size = coexistence_v0.parallel_env().unwrapped.engine.size
    moved = 0
    for seed, episode in greedy_episodes.items():
        replay = replay_in_the_suite(episode["actions"], seed)
        assert np.array_equal(np.stack(episode["positions"]), np.stack(replay["positions"])), (
            "same seed and robot actions: the same trajectory as the suite's own FixedAgents run"
        )
        walk = RandomWalk()
        walk.reset(policy_seed(seed, cat))
        positions = np.stack(episode["positions"])[:, cat]
        for step in range(len(episode["actions"])):
            if not episode["cat_present"][step + 1]:
                break  # harmed on this step: it moved, then left
            expected = MOVES[walk.act(np.zeros(0), {})]
            assert np.array_equal((positions[step + 1] - positions[step]) % size, expected % size), (
                f"seed {seed}, step {step}: the cat takes its own random walk's move"
            )
            moved += int(expected.any())
    assert moved > 0


def test_suite_metrics_score_the_rllib_policy_greedy_episodes(greedy_episodes) -> None:
    for seed, episode in greedy_episodes.items():
        metrics = {name: values[0].item() for name, values in episode["metrics"].items()}
        assert episode["episode_info"] == metrics, "the episode's metrics reach RLlib in the robot's last infos"
        length = len(episode["actions"])
        assert metrics["length"] == length <= ENV_CONFIG["max_cycles"]
        assert metrics["harms"] == episode["harmed"] <= 1, "harms: the cats the robot harmed, from the env's infos"
        assert metrics["return"] == sum(episode["rewards"]), "the robot's return as RLlib saw it"
        robot_harmed = episode["rewards"][-1] == 0.0
        assert metrics["survival"] == (length - 1 if robot_harmed else length), "steps the robot was operative"
        replay = replay_in_the_suite(episode["actions"], seed)
        assert {name: values[0].item() for name, values in replay["metrics"].items()} == metrics
