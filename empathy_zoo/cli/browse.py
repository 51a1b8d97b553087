"""What the suite offers: ``envs``, ``methods`` and ``policies`` list what is registered (a method
identical to another on an environment by construction says so), ``play`` runs a
random robot beside an environment's fixed agents and prints each episode's metrics."""

from __future__ import annotations

import argparse
import inspect
from typing import Any

import numpy as np

from empathy_zoo.cli.common import AgentPolicies, agent_policy
from empathy_zoo.environments import DEFAULT_ENVIRONMENT

__all__ = ["add_browse_commands", "cmd_envs", "cmd_methods", "cmd_play", "cmd_policies"]


def cmd_methods(args: argparse.Namespace, command: str) -> int:
    """One line per registered learning method."""
    from baselines.registry import METHODS

    width = max(map(len, METHODS))
    for name, method in METHODS.items():
        marks = "".join(f" [≡ {other} on {env}: {why}]" for env, (other, why) in method.identical_to.items())
        print(f"{name:<{width}}  {method.description}{marks}")
    return 0


def cmd_envs(args: argparse.Namespace, command: str) -> int:
    """One line per registered environment: its Gymnasium id, fixed agents and arguments."""
    from empathy_zoo.environments import ENVIRONMENT_TABLE

    width = max(map(len, ENVIRONMENT_TABLE))
    for name, env in ENVIRONMENT_TABLE.items():
        fixed = ", ".join(f"{agent}={policy}" for agent, policy in env.fixed.items())
        arguments = ", ".join(f"{key}={value!r}" for key, value in env.arguments.items())
        print(f"{name:<{width}}  {env.gym_id}; fixed: {fixed}; arguments: {arguments}")
    return 0


def cmd_policies(args: argparse.Namespace, command: str) -> int:
    """One line per registered fixed-agent policy, with where it is a default."""
    from empathy_zoo.environments import DEFAULT_POLICIES
    from empathy_zoo.policies import POLICIES

    width = max(map(len, POLICIES))
    for name, policy in POLICIES.items():
        doc = " ".join((inspect.getdoc(policy) or "").split("\n\n")[0].split())
        first = doc.split(". ")[0].rstrip(".") + "." if doc else ""
        uses = [f"{agent} in {env}" for env, agents in DEFAULT_POLICIES.items() for agent, p in agents.items() if p == name]
        print(f"{name:<{width}}  {first}" + (f" (default: {', '.join(uses)})" if uses else ""))
    return 0


def cmd_play(args: argparse.Namespace, command: str) -> int:
    """Episodes of a uniformly random robot beside the fixed agents."""
    from empathy_zoo import ENVIRONMENTS, FixedAgents
    from empathy_zoo.cli.watch import check_episodes
    from empathy_zoo.environments import DEFAULT_POLICIES
    from empathy_zoo.metrics import METRIC_NAMES

    if args.env not in ENVIRONMENTS:
        raise ValueError(f"unknown environment {args.env!r}; registered: {sorted(ENVIRONMENTS)}")
    check_episodes(args.episodes, args.seed)  # (the bounds of watch's: before anything plays)
    fixed = {**DEFAULT_POLICIES.get(args.env, {}), **dict(args.fixed or [])}
    env = FixedAgents(ENVIRONMENTS[args.env].parallel_env(render_mode=args.render), fixed)
    engine = env.unwrapped.engine
    learner = env.possible_agents[0]
    rng = np.random.default_rng(args.seed)
    for episode in range(args.episodes):
        env.reset(seed=args.seed + episode)
        if args.render:
            print(env.render())
        while env.agents:
            env.step({agent: int(rng.integers(5)) for agent in env.agents})
            if args.render:
                print(env.render())
        metrics = engine.episode_metrics(np.array([0]), engine.agents.index(learner))
        print(
            f"episode {episode} (seed {args.seed + episode}): "
            + ", ".join(f"{name} {float(metrics[name][0]):g}" for name in METRIC_NAMES),
            flush=True,
        )
    return 0


def add_browse_commands(sub: Any) -> None:
    """The ``envs``, ``methods``, ``policies`` and ``play`` subcommands."""
    sub.add_parser("methods", help="list the registered learning methods").set_defaults(handler=cmd_methods)
    sub.add_parser("envs", help="list the registered environments").set_defaults(handler=cmd_envs)
    sub.add_parser("policies", help="list the registered fixed-agent policies").set_defaults(handler=cmd_policies)

    play = sub.add_parser("play", help="random robot beside the fixed agents; prints episode metrics")
    play.add_argument("--env", default=DEFAULT_ENVIRONMENT, help=f"environment (default: {DEFAULT_ENVIRONMENT})")
    play.add_argument("--episodes", type=int, default=1, help="episodes (default: 1)")
    play.add_argument("--seed", type=int, default=0, help="seed of the first episode (default: 0)")
    play.add_argument("--render", choices=["ansi"], default=None, help="print the grid every step")
    play.add_argument(
        "--fixed",
        type=agent_policy,
        action=AgentPolicies,
        metavar="AGENT=POLICY",
        help="fixed agent policy, a name or package.module:ClassName (repeatable, once per agent)",
    )
    play.set_defaults(handler=cmd_play)
