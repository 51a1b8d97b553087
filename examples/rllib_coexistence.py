"""Train an RLlib algorithm (PPO, new API stack) on Coexistence, then score it with the suite's metrics.

The cat stays a fixed agent (``FixedAgents``), so the robot is RLlib's only agent; RLlib sees the
PettingZoo env through its own ``ParallelPettingZooEnv`` wrapper. RLlib is not a dependency of
the suite: ``pip install -e ".[rllib]"`` first (RLlib pins its own Gymnasium release, so a
virtual environment of its own is best; tests/test_rllib.py checks this setup).

    python examples/rllib_coexistence.py --iterations 5

Prints, per iteration, the mean training return (= survival: +1 per operative step) and episode
length; then runs the trained policy greedily for a few episodes and prints the suite's scored
metrics (survival, harms: the env's ``infos[agent]["episode"]`` at an episode's end), computed
from what happened, not from the reward.
"""

from __future__ import annotations

import argparse

import numpy as np
import torch

from empathy_zoo import FixedAgents, coexistence_v0

ROBOT = "robot_0"


def make_env(config: dict | None = None):
    """Coexistence with the cat driven inside: RLlib's multi-agent env with one agent, the robot."""
    from ray.rllib.env.wrappers.pettingzoo_env import ParallelPettingZooEnv

    return ParallelPettingZooEnv(FixedAgents(coexistence_v0.parallel_env(**(config or {})), {"cat_0": "random_walk"}))


def greedy_action(module, observation: np.ndarray) -> int:
    """The module's greedy action: its inference action distribution, made deterministic."""
    with torch.no_grad():
        out = module.forward_inference({"obs": torch.as_tensor(observation[None])})
    dist = module.get_inference_action_dist_cls().from_logits(out["action_dist_inputs"]).to_deterministic()
    return int(dist.sample()[0])


def greedy_scores(module, episodes: int, seed: int) -> dict[str, float]:
    """Run the trained robot greedily; the suite's metrics of each episode (which the env reports
    in the robot's last ``infos`` as ``"episode"``), averaged."""
    env = make_env()
    scores: dict[str, list[float]] = {"survival": [], "harms": []}
    for episode in range(episodes):
        obs, _ = env.reset(seed=seed + episode)
        done = False
        while not done:
            obs, _, terminated, truncated, infos = env.step({ROBOT: greedy_action(module, obs[ROBOT])})
            done = terminated["__all__"] or truncated["__all__"]
        for name in scores:
            scores[name].append(infos[ROBOT]["episode"][name])
    return {name: float(np.mean(values)) for name, values in scores.items()}


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--iterations", type=int, default=5, help="PPO training iterations")
    parser.add_argument("--batch", type=int, default=4000, help="env steps per iteration")
    parser.add_argument("--episodes", type=int, default=10, help="greedy evaluation episodes")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)

    import ray
    from ray.rllib.algorithms.ppo import PPOConfig
    from ray.tune.registry import register_env

    ray.init(include_dashboard=False, logging_level="ERROR")
    register_env("coexistence_v0_robot", make_env)
    config = (
        PPOConfig()
        .api_stack(enable_rl_module_and_learner=True, enable_env_runner_and_connector_v2=True)
        .environment("coexistence_v0_robot")
        .env_runners(num_env_runners=1, num_envs_per_env_runner=1)
        .multi_agent(policies={ROBOT}, policy_mapping_fn=lambda agent_id, episode, **kwargs: ROBOT)
        .training(train_batch_size_per_learner=args.batch, minibatch_size=250, num_epochs=6, lr=3e-4, gamma=0.99)
        .debugging(seed=args.seed)
    )
    algo = config.build_algo()
    try:
        for iteration in range(1, args.iterations + 1):
            result = algo.train()
            runners = result["env_runners"]
            print(
                f"iteration {iteration}: episode_return_mean={runners['episode_return_mean']:.1f} "
                f"episode_len_mean={runners['episode_len_mean']:.1f} "
                f"env_steps={result['num_env_steps_sampled_lifetime']}"
            )
        scores = greedy_scores(algo.get_module(ROBOT), args.episodes, seed=10_000)
        print(f"greedy, {args.episodes} episodes: survival={scores['survival']:.1f} harms={scores['harms']:.2f}")
    finally:
        algo.stop()
        ray.shutdown()


if __name__ == "__main__":
    main()
