"""The PettingZoo env reports each episode's metrics in ``infos`` at its end, exactly as the
vector env (and so the leaderboard) scores the same episode."""

from __future__ import annotations

import numpy as np
import pytest

from empathy_zoo import ENVIRONMENTS, FixedAgents
from empathy_zoo.environments import DEFAULT_POLICIES
from empathy_zoo.metrics import METRIC_NAMES
from empathy_zoo.vector import VectorEnv


@pytest.mark.parametrize("name", sorted(ENVIRONMENTS))
@pytest.mark.parametrize("seed", [0, 3, 11])
def test_the_last_infos_hold_the_metrics_the_vector_env_scores(name: str, seed: int) -> None:
    env = FixedAgents(ENVIRONMENTS[name].parallel_env(max_cycles=60), DEFAULT_POLICIES[name])
    vector = VectorEnv(name, 1, fixed=DEFAULT_POLICIES[name], max_cycles=60)
    [robot] = env.possible_agents
    env.reset(seed=seed)
    vector.reset(seed=[seed])
    actions = np.random.default_rng(seed).integers(0, 5, size=60)
    for t, action in enumerate(actions):
        _, _, _, _, infos = env.step({robot: int(action)})
        step = vector.step(np.array([[action]]))
        if env.agents:
            assert "episode" not in infos[robot] and step.finished["env"].size == 0
            continue
        scored = {key: step.finished[key][0].item() for key in (*METRIC_NAMES, "length")}
        assert infos[robot]["episode"] == pytest.approx(scored) and infos[robot]["episode"]["length"] == t + 1
        return
    pytest.fail("the episode did not end within max_cycles")
