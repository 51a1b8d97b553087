"""A uniformly random robot in Coexistence under the paper's rules and under the authors' code's.

Plays ``--episodes`` episodes (each environment one episode, seeded 0 … episodes − 1) with the
robot and the cat both choosing uniformly among the five actions, and prints per rule set: the
robot's survival (steps it stayed operative), harms it did per episode, and the share of episodes
in which it was harmed, each as ``[mean, standard error]``. The authors' episodes last ``max_cycles + 1`` steps (``steps >
max_steps``), so their rule set runs with ``max_cycles=501``.

    python benchmarks/coexistence_rules.py --episodes 4000
"""

from __future__ import annotations

import argparse
import json

import numpy as np

from empathy_zoo.engine.base import STAY
from empathy_zoo.engine.coexistence import CoexistenceEngine

RULE_SETS = {"paper": {"rules": "paper", "max_cycles": 500}, "authors": {"rules": "authors", "max_cycles": 501}}
"""What each rule set is played with."""


def random_robot(episodes: int, seed: int = 0, **kwargs: object) -> dict[str, object]:
    """Mean survival, harms per episode and the share of episodes the robot was harmed in."""
    engine = CoexistenceEngine(num_envs=episodes, **kwargs)  # type: ignore[arg-type]
    engine.reset(seeds=list(range(seed, seed + episodes)))
    rng = np.random.default_rng(seed)
    over = np.zeros(episodes, dtype=bool)
    harmed = np.zeros(episodes, dtype=bool)
    metrics = engine.episode_metrics(np.arange(episodes))
    while not over.all():
        actions = np.where(engine.present, rng.integers(0, 5, size=engine.present.shape), STAY)
        events = engine.step(actions)
        ended = events.episode_over | events.terminated[:, 0] | events.truncated[:, 0]
        if ended.any():
            ids = np.flatnonzero(ended)
            first = ids[~over[ids]]  # (an environment's later episodes are played, not counted)
            now = engine.episode_metrics(first)
            for name in metrics:
                metrics[name][first] = now[name]
            harmed[first] = events.harmed_by[first, 0] >= 0
            over[first] = True
            engine.reset(ids)

    def mean_and_error(values: np.ndarray, digits: int) -> list[float]:
        """The mean and its standard error."""
        return [round(float(np.mean(values)), digits), round(float(np.std(values, ddof=1) / np.sqrt(len(values))), digits)]

    return {
        "episodes": episodes,
        "survival": mean_and_error(metrics["survival"], 1),
        "harms_per_episode": mean_and_error(metrics["harms"], 3),
        "robot_harmed_share": mean_and_error(harmed.astype(float), 3),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=4_000)
    parser.add_argument("--seed", type=int, default=0, help="first environment seed (and the actions' generator)")
    args = parser.parse_args()
    for name, kwargs in RULE_SETS.items():
        print(json.dumps({"rules": name, **kwargs, **random_robot(args.episodes, args.seed, **kwargs)}), flush=True)


if __name__ == "__main__":
    main()
